#pragma once
/// @file A program's command line as text, for what a run records of itself
/// (a session file's metadata).
#include <string>

namespace haptel::cli {

/// The command line as a shell would take it back: "haptel" then argv's
/// words (argv[0] the subcommand, e.g. "run"), each with a space, a quote or
/// a shell character single-quoted.
std::string CommandLine(int argc, const char* const* argv);

}  // namespace haptel::cli
