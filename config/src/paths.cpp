#include "haptel/config/paths.hpp"

#include "haptel/core/args.hpp"

namespace haptel {

std::filesystem::path ShippedFile(const std::string& relative) {
  if (std::filesystem::exists(relative)) return relative;
  return std::filesystem::path(HAPTEL_SOURCE_DIR) / relative;
}

std::string NotRegularFile(const std::filesystem::path& file) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(status)) return "";
  if (std::filesystem::is_directory(status)) return "a folder";
  if (!std::filesystem::is_regular_file(status))
    return "not a regular file (a FIFO, a device or a socket)";
  return "";
}

void CheckFileOption(const std::string& option, const std::filesystem::path& file,
                     const std::string& expected) {
  if (const std::string what = NotRegularFile(file); !what.empty()) {
    throw UsageError("option --" + option + ": '" + file.string() + "' is " + what + "; expected " +
                     expected);
  }
}

}  // namespace haptel
