#pragma once
/// @file A program's command line as text, for what a run records of itself
/// (a session file's metadata), and read back into its words.
#include <string>
#include <string_view>
#include <vector>

namespace haptel::cli {

/// The command line as a shell would take it back: "haptel" then argv's
/// words (argv[0] the subcommand, e.g. "run"), each with a space, a quote or
/// a shell character single-quoted.
std::string CommandLine(int argc, const char* const* argv);

/// A line CommandLine wrote, back into its words (quotes taken off). Throws
/// UsageError on an unterminated quote.
std::vector<std::string> CommandLineWords(const std::string& line);

/// Whether argv (after argv[0]) holds `option` as a word of its own: how a
/// subcommand picks its mode (e.g. `haptel replay --info`) before its own
/// Args parse the rest.
bool HasOption(int argc, const char* const* argv, std::string_view option);

}  // namespace haptel::cli
