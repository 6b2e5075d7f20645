#pragma once
/// @file The session `haptel run` drives, set up from its options, and the
/// steps a study repeats for each trial: set a session up from the same
/// options, run it and record it. The command line itself (its usage, its
/// summary, its JSON line, its exit code) is app/'s (app/run_command.hpp).
#include <atomic>
#include <cstdint>
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

/// `haptel run`'s options (argv[0] is "run"; see its --help): the words a
/// study's trial and each vehicle of a fleet are set up from too.
Args ParseRunArgs(int argc, const char* const* argv);

/// The session `haptel run` would drive for these options: every file read
/// and checked against the others; nothing started. Throws UsageError and
/// ConfigError (bad input).
SessionSetup RunSetupFromArgs(const Args& args);

/// The session file's metadata (configuration, vehicle, device, operator,
/// interfaces) and attachments (the run's, vehicle's, device's and track's
/// files) from `setup`; the caller adds the command line and, for a study,
/// its own metadata.
void DescribeSessionFile(SessionSetup& setup);

/// Runs the session, then saves it into `recorder` — or, if the database
/// fails at the end, into a fallback file beside it — with its picture.
/// Throws only for parts that cannot be set up (nothing moved).
/// `also` is written in the run's own transaction (e.g. a study's trial row);
/// `trial` says in the fallback file whose trial the run was.
RecordedRun RunAndRecord(const SessionSetup& setup, Recorder& recorder,
                         const std::atomic<bool>& interrupted, const Recorder::AlsoSave& also = {},
                         const std::optional<record::TrialOfRun>& trial = std::nullopt);

}  // namespace haptel::mediator
