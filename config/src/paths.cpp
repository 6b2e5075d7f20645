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

void CheckOutputFileOption(const std::string& option, const std::filesystem::path& file,
                           const std::string& expected) {
  CheckFileOption(option, file, expected);
  const std::filesystem::path folder = file.parent_path().empty() ? "." : file.parent_path();
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (!std::filesystem::is_directory(folder)) {
    throw UsageError("option --" + option + ": the folder '" + folder.string() +
                     "' cannot be made (" + (ec ? ec.message() : "a file is in the way") +
                     "); expected a file in a folder that exists or can be made");
  }
}

}  // namespace haptel
