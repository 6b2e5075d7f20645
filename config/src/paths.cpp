#include "haptel/config/paths.hpp"

namespace haptel {

std::filesystem::path ShippedFile(const std::string& relative) {
  if (std::filesystem::exists(relative)) return relative;
  return std::filesystem::path(HAPTEL_SOURCE_DIR) / relative;
}

}  // namespace haptel
