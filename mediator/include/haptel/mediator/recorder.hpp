#pragma once
/// @file Records finished runs in a SQLite database.
///
/// One run is written in one transaction (the run row and its gate splits), so
/// an interrupted write leaves nothing half-written.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

struct sqlite3;

namespace haptel::mediator {

/// One gate of a lap: whether it was passed between its posts, and when its
/// line was crossed, in s since the lap started (negative: never reached).
struct GateSplit {
  int gate = 0;
  bool passed = false;
  double split_s = -1.0;
};

/// Everything a run reports, as stored in the database.
struct RunRecord {
  int64_t id = 0;                ///< set by Save / Load
  int64_t started_wall_ns = 0;   ///< CLOCK_REALTIME at session start
  std::string config_name;
  std::string track;
  std::string interface;
  std::string vehicle;
  bool completed = false;
  std::string outcome;           ///< "completed", "lap cap", "vehicle lost", "interrupted", ...
  double lap_time_s = 0.0;
  int gates_passed = 0;
  int gates_total = 0;
  int gates_missed = 0;
  int obstacles_touched = 0;
  int vehicle_pid = 0;
  double servo_rate_hz = 0.0;
  double servo_period_p99_us = 0.0;
  double command_rtt_ms_p50 = 0.0;
  double command_rtt_ms_p99 = 0.0;
  int64_t video_frames = 0;
  double video_fps = 0.0;
  double video_latency_ms_p50 = 0.0;
  std::vector<GateSplit> splits;
};

class Recorder {
 public:
  /// Opens (creating it and its parent folders if needed) the database and its
  /// schema. Throws std::runtime_error naming the file on failure.
  explicit Recorder(const std::filesystem::path& database);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Writes the run and its splits in one transaction; returns the run id.
  /// On any failure rolls back and throws std::runtime_error.
  int64_t Save(const RunRecord& run);

  /// All runs, oldest first, with their splits (gate order).
  std::vector<RunRecord> LoadAll() const;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
};

}  // namespace haptel::mediator
