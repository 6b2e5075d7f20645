#include "haptel/mcap/records.hpp"

namespace haptel::mcap {

std::string_view CompressionName(Compression compression) {
  switch (compression) {
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
    case Compression::kNone:
      break;
  }
  return "";
}

Compression ParseCompression(std::string_view name) {
  if (name == "zstd") return Compression::kZstd;
  if (name == "lz4") return Compression::kLz4;
  if (name == "none" || name.empty()) return Compression::kNone;
  throw std::invalid_argument("MCAP compression: expected zstd, lz4 or none, got '" +
                              std::string(name) + "'");
}

}  // namespace haptel::mcap
