#pragma once
/// @file `haptel run`: one lap from the command line — and the steps a study
/// repeats for each trial: run a session that is set up, record it, print
/// its summary and its JSON line.
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "haptel/core/args.hpp"
#include "haptel/mediator/run_record.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/record/unsaved_run.hpp"

namespace haptel::mediator {

/// A session's result and where it was stored.
struct RecordedRun {
  SessionResult result;
  int64_t run_id = 0;             ///< its row in the database (0: not recorded)
  std::filesystem::path unsaved;  ///< the fallback file when the database failed
  std::string save_error;         ///< why the database did not take it ("" when it did)
};

/// `haptel run`'s options (argv[0] is "run"; see its --help).
Args ParseRunArgs(int argc, const char* const* argv);

/// The session `haptel run` would drive for these options: every file read
/// and checked against the others; nothing started. Throws UsageError and
/// ConfigError (bad input).
SessionSetup RunSetupFromArgs(const Args& args);

/// Runs the session, then saves it into `recorder` — or, if the database
/// fails at the end, into a fallback file beside it — with its picture.
/// Throws only for parts that cannot be set up (nothing moved).
/// `also` is written in the run's own transaction (e.g. a study's trial row);
/// `trial` says in the fallback file whose trial the run was.
RecordedRun RunAndRecord(const SessionSetup& setup, Recorder& recorder,
                         const std::atomic<bool>& interrupted, const Recorder::AlsoSave& also = {},
                         const std::optional<record::TrialOfRun>& trial = std::nullopt);

/// The process exit code: kExitNotRecorded when the database did not take the
/// run, else kExitOutputFailed when the --record MP4 or the vehicle's CAN
/// bus log failed, else the outcome's.
int ExitCode(const RecordedRun& run);

/// The lines `haptel run` prints after a lap.
void PrintRunSummary(std::FILE* out, const SessionSetup& setup, const RecordedRun& run);
/// The one JSON line of `haptel run --json` (no newline).
std::string RunJson(const SessionSetup& setup, const RecordedRun& run);

/// `haptel run`; argv[0] is "run". Returns the exit code.
int RunCommand(int argc, const char* const* argv);

}  // namespace haptel::mediator
