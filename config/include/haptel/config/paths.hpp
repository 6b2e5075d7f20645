#pragma once
/// @file Where shipped configuration files are found.
#include <filesystem>
#include <string>

namespace haptel {

/// A shipped file named relative to the repository root, e.g.
/// "config/haptel.yaml": as given when it exists from the working directory,
/// else under the source tree the binaries were built from.
std::filesystem::path ShippedFile(const std::string& relative);

}  // namespace haptel
