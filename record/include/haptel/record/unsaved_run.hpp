#pragma once
/// @file A run the database could not take, kept as JSON next to it.
///
/// The session checks the database before anything starts (Recorder), but a
/// save can still fail at the end: the disk is full, the file was deleted or
/// replaced during the run. The lap's results are then written here, in full,
/// so nothing measured is lost.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "haptel/record/recorder.hpp"

namespace haptel::record {

/// The whole run as one JSON object: every field of RunRecord under its own
/// name, with its splits, switches, path, contacts and counters (as an object
/// {"name": value}); numbers with full precision, NaN and infinities as null.
std::string RunRecordJson(const RunRecord& run);

/// The fallback file for `database` at `wall_ns` (CLOCK_REALTIME):
/// `<database>.unsaved-<UTC, e.g. 20240501T123456.789Z>.json`.
std::filesystem::path UnsavedRunPath(const std::filesystem::path& database, int64_t wall_ns);

/// The study trial a run was driven for: without it, a run kept in a file
/// could not be told from the others, nor put back where it belongs.
struct TrialOfRun {
  std::string study;  ///< the study's name
  std::string participant;
  int position = 0;  ///< in the participant's order (0: a practice lap)
  std::string condition;
  int repetition = 1;
};

/// Writes RunRecordJson(run) to UnsavedRunPath(database, wall_ns) — or, when
/// that folder cannot take it, to a file of the same name in the system's
/// temporary folder — and returns the file written. Never overwrites a file:
/// a name taken gets "-2", "-3", ... before ".json". With `trial`, the object
/// begins with "trial":{"study","participant","position","condition",
/// "repetition"}.
/// Throws std::runtime_error naming both places when neither can be written.
std::filesystem::path WriteUnsavedRun(const RunRecord& run, const std::filesystem::path& database,
                                      int64_t wall_ns,
                                      const std::optional<TrialOfRun>& trial = std::nullopt);

}  // namespace haptel::record
