#pragma once
/// @file Where shipped configuration files are found, and the check a path
/// gets before it is opened.
#include <filesystem>
#include <string>

namespace haptel {

/// A shipped file named relative to the repository root, e.g.
/// "config/haptel.yaml": as given when it exists from the working directory,
/// else under the source tree the binaries were built from.
std::filesystem::path ShippedFile(const std::string& relative);

/// What `file` is when it exists and is not a regular file: "a folder", or
/// "not a regular file (a FIFO, a device or a socket)"; "" when it is a
/// regular file or does not exist (creating or opening it says the rest).
/// Opening a FIFO waits for its other end, for ever and deaf to SIGINT and
/// SIGTERM, so every path a file is read from or written to is checked first.
std::string NotRegularFile(const std::filesystem::path& file);

/// For a command-line option naming a file to read or write (--record,
/// --trace, --trace-in, --database): throws UsageError "option --OPTION:
/// 'FILE' is a folder; expected EXPECTED" (or is not a regular file) before
/// anything opens it. Nothing for a regular or missing file.
void CheckFileOption(const std::string& option, const std::filesystem::path& file,
                     const std::string& expected);

/// For a command-line option naming a file to write (--record): the
/// CheckFileOption check, then its folder made, as --database and --trace
/// make theirs; throws UsageError "option --OPTION: the folder 'F' cannot be
/// made (WHY); expected a file in a folder that exists or can be made".
void CheckOutputFileOption(const std::string& option, const std::filesystem::path& file,
                           const std::string& expected);

}  // namespace haptel
