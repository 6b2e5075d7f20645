#pragma once
/// @file `haptel study`: run an A/B study from its file, resuming where it
/// stopped, report on it, and plan it (how many participants it needs).
///
///     haptel study run FILE [--json] [--database FILE]
///     haptel study report DATABASE --study NAME [--out DIR] [--json]
///     haptel study power FILE [--participants 4,8,12,16] [--simulations N] [--pool M] [--json]

namespace haptel::study {

/// argv[0] is "study". Returns the exit code.
int StudyCommand(int argc, const char* const* argv);

}  // namespace haptel::study
