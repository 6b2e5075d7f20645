#pragma once
/// @file What `haptel study power FILE` does below its command line (which
/// app/'s `study_power_command.cpp` parses): a pool of simulated participants (the
/// study file's driver profiles, varied; power_pool.hpp) runs the study's
/// trials, in simulated time, in worker processes of its own; the Monte
/// Carlo of power.hpp then draws balanced samples of each participant count
/// from the pool and analyses them as the report does.
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptel/study/power.hpp"

namespace haptel::study {

/// `haptel study power`'s options, as its command line gives them.
struct StudyPowerOptions {
  std::filesystem::path file;  ///< the study file
  /// The participant counts, the simulations per count and the seed (the
  /// pool's profiles and the draws); the rest is PowerOptions' default.
  PowerOptions power;
  std::optional<int> pool;  ///< simulated participants in the pool (default 8 per order row)
  int jobs = 2;             ///< trials at the same time, one worker process each
  /// Set: this process is worker N of the pool (spawned by the command itself).
  std::optional<int> worker;
  std::optional<int> domain;  ///< the trials' DDS domain (real time: worker w's N + w)
  std::optional<std::filesystem::path> out;  ///< where the files go
  bool json = false;
  bool verbose = false;
  bool real_time = false;  ///< the pool's trials in real time, each with its vehicle process
  /// The command's words ("study", "power", FILE, options): each worker
  /// process is `haptel` with these and `--worker N`.
  std::vector<std::string> words;
};

/// Runs the pool (or, as a worker, its share of it), estimates the power
/// and writes power.csv, power.png and pool.csv; prints the table (and with
/// `json` one JSON line). Returns the exit code (core/cli.hpp's). What
/// cannot start (the study file, options it cannot take, an output folder
/// that cannot be written) throws cli::InputError before any trial runs.
int RunStudyPower(const StudyPowerOptions& options, const std::atomic<bool>& interrupted);

}  // namespace haptel::study
