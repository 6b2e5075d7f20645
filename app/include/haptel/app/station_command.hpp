#pragma once
/// @file `haptel station`: the control room's command line (usage, options,
/// summary, JSON line, exit code) over what station/ does.

namespace haptel::app {

/// `haptel station --vehicle NAME --camera CAMERA [options]`; `argv[0]` is
/// "station". Exit codes as station::ExitCode, 2 for bad arguments.
int StationCommand(int argc, const char* const* argv);

}  // namespace haptel::app
