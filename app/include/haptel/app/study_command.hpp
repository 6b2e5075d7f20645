#pragma once
/// @file `haptel study`: run an A/B study from its file, resuming where it
/// stopped, report on it, and plan it (how many participants it needs).
///
///     haptel study run FILE [--json] [--database FILE]
///     haptel study report DATABASE --study NAME [--out DIR] [--json]
///     haptel study power FILE [--participants 4,8,12,16] [--simulations N] [--pool M] [--json]

namespace haptel::app {

/// argv[0] is "study". Returns the exit code.
int StudyCommand(int argc, const char* const* argv);

/// The subcommands, each parsing its own options (argv[0] is "study",
/// argv[1] its name) and calling what study/ does: study_run.hpp,
/// study/report/, study_power.hpp. Each returns the exit code.
int StudyRunCommand(int argc, const char* const* argv);
int StudyReportCommand(int argc, const char* const* argv);
int StudyPowerCommand(int argc, const char* const* argv);

}  // namespace haptel::app
