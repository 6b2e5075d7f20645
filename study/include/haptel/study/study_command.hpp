#pragma once
/// @file `haptel study`: run an A/B study from its file, resuming where it
/// stopped, and report on it.
///
///     haptel study run FILE [--json] [--database FILE]
///     haptel study report DATABASE --study NAME [--out DIR] [--json]

namespace haptel::study {

/// argv[0] is "study". Returns the exit code.
int StudyCommand(int argc, const char* const* argv);

}  // namespace haptel::study
