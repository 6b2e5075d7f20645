#pragma once
/// @file `haptel run`: one lap from the command line, or with --fleet one
/// operator and several vehicles. The command line only: the session is set
/// up and run by the mediator (mediator/run_setup.hpp, mediator/fleet.hpp).
///
///     haptel run [options]              (haptel run --help lists them)
///     haptel run --fleet FILE [options]
#include <atomic>
#include <cstdio>
#include <string>

#include "haptel/mediator/run_setup.hpp"

namespace haptel::app {

/// `haptel run`; argv[0] is "run". With --fleet, RunFleetCommand. Returns
/// the exit code.
int RunCommand(int argc, const char* const* argv);

/// `haptel run --fleet FILE ...` (argv[0] is "run"): sets up each vehicle
/// as `haptel run` would with the fleet file's vehicle, world, name and
/// interface, runs the fleet, records one row per vehicle, prints a table
/// on stderr and, with --json, one line on stdout. Returns the exit code.
int RunFleetCommand(int argc, const char* const* argv, const std::atomic<bool>& interrupted);

/// The process exit code: kExitNotRecorded when the database did not take the
/// run, else kExitOutputFailed when the --record MP4 or the vehicle's CAN
/// bus log failed, else the outcome's.
int ExitCode(const mediator::RecordedRun& run);

/// The lines `haptel run` prints after a lap.
void PrintRunSummary(std::FILE* out, const mediator::SessionSetup& setup,
                     const mediator::RecordedRun& run);
/// The one JSON line of `haptel run --json` (no newline).
std::string RunJson(const mediator::SessionSetup& setup, const mediator::RecordedRun& run);

}  // namespace haptel::app
