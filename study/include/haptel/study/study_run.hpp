#pragma once
/// @file What `haptel study run FILE` does below its command line (which
/// app/'s `study_run_command.cpp` parses): the study planned and checked against
/// its run configuration, its database, console and tables opened, the
/// planned trials run in order, each a session like `haptel run`'s recorded
/// as it finishes (a second start resumes at the first unfinished one), and
/// the schedule reported.
#include <atomic>
#include <optional>
#include <string>

#include "haptel/study/console.hpp"

namespace haptel::study {

/// `haptel study run`'s options, as its command line gives them.
struct StudyRunOptions {
  std::filesystem::path file;           ///< the study file
  std::optional<std::string> database;  ///< overrides the study's and the run configuration's
  std::string domain;           ///< the trials' vehicles' DDS domain ("": the run configuration's)
  bool json = false;            ///< end with one JSON line: the trials and per-condition totals
  bool verbose = false;         ///< the sessions' own progress lines
  bool simulated_time = false;  ///< each trial in simulated time (synthetic studies only)
  /// Serve the experimenter's console (a person study always does), with
  /// `console_options` (port, address, HTTPS).
  bool console = false;
  ConsoleOptions console_options;
};

/// Runs the study and prints its schedule (and with `json` one JSON line);
/// returns the exit code (core/cli.hpp's). What cannot start (the study
/// file, its run configuration, options the study cannot take, the
/// database, the console's port) throws cli::InputError before any trial
/// runs. `interrupted` (the stop signals) ends the study before its next
/// trial, and ends the one under way.
int RunStudy(const StudyRunOptions& options, const std::atomic<bool>& interrupted);

}  // namespace haptel::study
