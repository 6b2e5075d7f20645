// Tests for haptel::record::Recorder: round trip (with switches, path,
// contacts and counters), folder creation, errors naming the file (a folder,
// a path under a file, garbage, damaged inner pages, a lock, a newer or
// foreign schema), migration of v1 and v2 databases, rollback of a failing
// save, a file deleted under an open Recorder, the fallback file of a run the
// database did not take, and that a process killed in the middle of a write
// leaves no half-written run behind.
#include <poll.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "haptel/record/recorder.hpp"
#include "haptel/record/unsaved_run.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using haptel::record::ContactPoint;
using haptel::record::GateSplit;
using haptel::record::PathPoint;
using haptel::record::Recorder;
using haptel::record::RunCounter;
using haptel::record::RunRecord;
using haptel::record::SwitchRecord;

namespace {

/// A fresh, uniquely named folder under $HAPTEL_TEST_TMP (or the system temp
/// folder), removed with everything in it at scope exit.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const char* env = std::getenv("HAPTEL_TEST_TMP");
    const fs::path base =
        (env != nullptr && *env != '\0') ? fs::path(env) : fs::temp_directory_path();
    path_ = base / ("haptel-recorder-" + std::to_string(::getpid()) + "-" +
                    std::to_string(counter.fetch_add(1)));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// Kills and reaps a forked child if the test leaves early.
class ChildGuard {
 public:
  /// Returned by Wait for a child that has not ended (never a wait status).
  static constexpr int kStillRunning = -1;

  explicit ChildGuard(pid_t pid) : pid_(pid) {}
  ~ChildGuard() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      Wait(10.0);
    }
  }
  ChildGuard(const ChildGuard&) = delete;
  ChildGuard& operator=(const ChildGuard&) = delete;

  /// Waits up to `timeout_s` for the child and returns its wait status, or
  /// kStillRunning: a child that hangs fails the test instead of hanging it.
  int Wait(double timeout_s) {
    int status = 0;
    const bool ended = haptel::test::WaitFor(
        [&] {
          pid_t got = 0;
          while ((got = ::waitpid(pid_, &status, WNOHANG)) < 0 && errno == EINTR) {
          }
          return got == pid_;
        },
        timeout_s);
    if (!ended) return kStillRunning;
    pid_ = -1;
    return status;
  }
  pid_t pid() const { return pid_; }

 private:
  pid_t pid_;
};

RunRecord MakeRun(int n, int split_count) {
  RunRecord run;
  run.started_wall_ns = 1'714'566'896'000'000'000 + int64_t{n} * 60'000'000'000 + 123'456'789;
  run.config_name = "study-A/" + std::to_string(n);
  run.track = "grand prix, O'Brien's \"hall\"; DROP TABLE runs; --";  // bound, not formatted
  run.interface = (n % 2 == 0) ? "gesture" : "cockpit+hud";
  run.vehicle = "tank-sim Zürich";
  run.vehicle_kind = (n % 2 == 0) ? "can-robot-sim" : "sim-robot";
  run.predict = n % 2 == 1;
  run.link_fault = n % 2 == 1 ? "delay=0.2s,jitter=0s,loss=0" : "";
  run.prediction_error_m_p50 = n % 3 == 0 ? -1.0 : 0.004 * n;  // -1: none (stored as NULL)
  run.speedup = n % 2 == 0 ? -1.0 : 12.5 * n;  // -1: a real-time run (stored as NULL)
  run.controller_errors =
      n % 2 == 0 ? -1 : (n % 4 == 1 ? 0 : 0x0008);  // -1: no servo controller (NULL)
  run.video_kbps = 850.5 + n;
  run.video_stale_s = 0.25 * n;
  run.disengaged_s = 1.5 + 0.25 * n;
  run.pseudo_haptic_gain_mean =  // NaN: the device does not bend the hand (NULL)
      n % 2 == 0 ? std::numeric_limits<double>::quiet_NaN() : 0.375 + 0.01 * n;
  run.ff_effects_played = n % 2 == 0 ? 0 : 5'000'000'000LL + n;  // needs 64 bits
  run.prediction_error_m_p95 = n % 3 == 0 ? -1.0 : 0.011 * n;
  run.completed = (n % 2 == 0);
  run.outcome = run.completed ? "completed" : "lap cap";
  run.lap_time_s = 110.25 + n;
  run.gates_passed = 4 - n % 2;
  run.gates_total = 5;
  run.gates_missed = 1 + n % 2;
  run.obstacles_touched = 3 * n + 1;
  run.vehicle_pid = 4000 + n;
  run.servo_rate_hz = 998.5 + n;
  run.servo_period_p99_us = 1042.125;
  run.command_rtt_ms_p50 = 1.5 + 0.1 * n;
  run.command_rtt_ms_p99 = 7.75;
  run.video_frames = 9'000'000'000LL + n;  // needs 64 bits
  run.video_fps = 29.97;
  run.video_latency_ms_p50 = 85.0 / 3.0;
  run.operator_kind = (n % 2 == 0) ? "auto" : "person";
  run.device = "sim arms « left/right »";
  run.distance_m = 7.125 + n;
  run.view_fps = 59.94;
  run.view_frame_p99_ms = 17.5 + n;
  run.video_to_screen_ms_p50 = 41.0 / 3.0;
  run.video_to_screen_ms_p99 = 88.25;
  run.picture = "/data/runs/pictures/run-" + std::to_string(n) + ".png";
  for (int g = 0; g < split_count; ++g) {
    GateSplit split;
    split.gate = g;
    split.passed = (g + n) % 3 != 0;
    split.split_s = split.passed ? 12.5 * (g + 1) + 0.001 * n : -1.0;
    run.splits.push_back(split);
  }
  run.switches = {{3.25, "gesture", "cockpit"}, {9.5 + n, "cockpit", "gesture"}};
  for (int i = 0; i < 20 + n; ++i) {
    run.path.push_back({0.05 * i, 0.01 * i - 1.0 / 3.0, -0.02 * i, 0.1 * (i % 7) - 0.2});
  }
  run.contacts = {{0.35, 0.5, -0.25}, {0.85 + n, -1.0 / 7.0, 2.0}};
  run.servo_target_hz = 1000.0;
  run.servo_rate_short = n % 2 == 1;
  run.physics_rate_hz = 306.5 + n;
  run.physics_target_hz = 10000.0;
  run.physics_rate_short = true;
  // The truth's lap (v16): not judged, completed with its finish projected,
  // or not completed.
  run.truth_lap.judged = n % 3 != 0;
  run.truth_lap.completed = n % 3 == 1;
  run.truth_lap.projected = n % 3 == 1;
  if (n % 3 == 1) run.truth_lap.lap_time_s = 111.5 + n;
  run.truth_lap.gates_passed = n % 3 == 0 ? 0 : 3 + n % 3;
  run.truth_lap.gates_missed = n % 3 == 2 ? 2 : 0;
  run.counters = {{"servo_overruns", uint64_t(3 + n)},
                  {"servo_forces_clamped", 0},
                  {"video_frames_dropped", uint64_t{1} << 40}};  // needs more than 32 bits
  return run;
}

bool SameReal(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

/// Every stored field equal (ids compared separately).
void CheckSame(const RunRecord& got, const RunRecord& want) {
  CHECK(got.started_wall_ns == want.started_wall_ns);
  CHECK(got.config_name == want.config_name);
  CHECK(got.track == want.track);
  CHECK(got.interface == want.interface);
  CHECK(got.vehicle == want.vehicle);
  CHECK(got.vehicle_kind == want.vehicle_kind);
  CHECK(got.predict == want.predict);
  CHECK(got.link_fault == want.link_fault);
  CHECK(got.prediction_error_m_p50 == want.prediction_error_m_p50);
  CHECK(got.video_kbps == want.video_kbps);
  CHECK(got.video_stale_s == want.video_stale_s);
  CHECK(got.prediction_error_m_p95 == want.prediction_error_m_p95);
  CHECK(got.speedup == want.speedup);
  CHECK(got.controller_errors == want.controller_errors);
  CHECK(SameReal(got.disengaged_s, want.disengaged_s));
  CHECK(SameReal(got.pseudo_haptic_gain_mean, want.pseudo_haptic_gain_mean));
  CHECK(got.ff_effects_played == want.ff_effects_played);
  CHECK(got.truth_lap.judged == want.truth_lap.judged);
  CHECK(got.truth_lap.completed == want.truth_lap.completed);
  CHECK(SameReal(got.truth_lap.lap_time_s, want.truth_lap.lap_time_s));
  CHECK(got.truth_lap.projected == want.truth_lap.projected);
  CHECK(got.truth_lap.gates_passed == want.truth_lap.gates_passed);
  CHECK(got.truth_lap.gates_missed == want.truth_lap.gates_missed);
  CHECK(got.completed == want.completed);
  CHECK(got.outcome == want.outcome);
  CHECK(SameReal(got.lap_time_s, want.lap_time_s));
  CHECK(got.gates_passed == want.gates_passed);
  CHECK(got.gates_total == want.gates_total);
  CHECK(got.gates_missed == want.gates_missed);
  CHECK(got.obstacles_touched == want.obstacles_touched);
  CHECK(got.vehicle_pid == want.vehicle_pid);
  CHECK(SameReal(got.servo_rate_hz, want.servo_rate_hz));
  CHECK(SameReal(got.servo_period_p99_us, want.servo_period_p99_us));
  CHECK(SameReal(got.command_rtt_ms_p50, want.command_rtt_ms_p50));
  CHECK(SameReal(got.command_rtt_ms_p99, want.command_rtt_ms_p99));
  CHECK(got.video_frames == want.video_frames);
  CHECK(SameReal(got.video_fps, want.video_fps));
  CHECK(SameReal(got.video_latency_ms_p50, want.video_latency_ms_p50));
  CHECK(got.operator_kind == want.operator_kind);
  CHECK(got.device == want.device);
  CHECK(SameReal(got.distance_m, want.distance_m));
  CHECK(SameReal(got.view_fps, want.view_fps));
  CHECK(SameReal(got.view_frame_p99_ms, want.view_frame_p99_ms));
  CHECK(SameReal(got.video_to_screen_ms_p50, want.video_to_screen_ms_p50));
  CHECK(SameReal(got.video_to_screen_ms_p99, want.video_to_screen_ms_p99));
  CHECK(got.picture == want.picture);
  CHECK(SameReal(got.servo_target_hz, want.servo_target_hz));
  CHECK(got.servo_rate_short == want.servo_rate_short);
  CHECK(SameReal(got.physics_rate_hz, want.physics_rate_hz));
  CHECK(SameReal(got.physics_target_hz, want.physics_target_hz));
  CHECK(got.physics_rate_short == want.physics_rate_short);
  REQUIRE(got.counters.size() == want.counters.size());
  for (size_t i = 0; i < want.counters.size(); ++i) {
    CHECK(got.counters[i].name == want.counters[i].name);
    CHECK(got.counters[i].value == want.counters[i].value);
  }
  REQUIRE(got.splits.size() == want.splits.size());
  for (size_t i = 0; i < want.splits.size(); ++i) {
    CHECK(got.splits[i].gate == want.splits[i].gate);
    CHECK(got.splits[i].passed == want.splits[i].passed);
    CHECK(SameReal(got.splits[i].split_s, want.splits[i].split_s));
  }
  REQUIRE(got.switches.size() == want.switches.size());
  for (size_t i = 0; i < want.switches.size(); ++i) {
    CHECK(got.switches[i].t_s == want.switches[i].t_s);
    CHECK(got.switches[i].from == want.switches[i].from);
    CHECK(got.switches[i].to == want.switches[i].to);
  }
  REQUIRE(got.path.size() == want.path.size());
  for (size_t i = 0; i < want.path.size(); ++i) {
    INFO("path point " << i);
    CHECK(got.path[i].t_s == want.path[i].t_s);
    CHECK(got.path[i].x == want.path[i].x);
    CHECK(got.path[i].y == want.path[i].y);
    CHECK(got.path[i].speed_mps == want.path[i].speed_mps);
  }
  REQUIRE(got.contacts.size() == want.contacts.size());
  for (size_t i = 0; i < want.contacts.size(); ++i) {
    CHECK(got.contacts[i].t_s == want.contacts[i].t_s);
    CHECK(got.contacts[i].x == want.contacts[i].x);
    CHECK(got.contacts[i].y == want.contacts[i].y);
  }
}

/// Raw connection for inspecting the file behind the Recorder's back.
struct RawDb {
  explicit RawDb(const fs::path& file) {
    REQUIRE(sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                            nullptr) == SQLITE_OK);
    sqlite3_busy_timeout(db, 2000);
  }
  ~RawDb() { sqlite3_close_v2(db); }
  RawDb(const RawDb&) = delete;
  RawDb& operator=(const RawDb&) = delete;

  int64_t Integer(const char* sql) const {
    sqlite3_stmt* stmt = nullptr;
    REQUIRE(sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) == SQLITE_OK);
    const int rc = sqlite3_step(stmt);
    const int64_t value = rc == SQLITE_ROW ? sqlite3_column_int64(stmt, 0) : -1;
    sqlite3_finalize(stmt);
    REQUIRE(rc == SQLITE_ROW);
    return value;
  }
  std::string Text(const char* sql) const {
    sqlite3_stmt* stmt = nullptr;
    REQUIRE(sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) == SQLITE_OK);
    const int rc = sqlite3_step(stmt);
    std::string value;
    if (rc == SQLITE_ROW && sqlite3_column_text(stmt, 0) != nullptr) {
      value = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    }
    sqlite3_finalize(stmt);
    REQUIRE(rc == SQLITE_ROW);
    return value;
  }
  void Exec(const char* sql) const {
    INFO(sql);
    REQUIRE(sqlite3_exec(db, sql, nullptr, nullptr, nullptr) == SQLITE_OK);
  }

  sqlite3* db = nullptr;
};

/// Expects `make()` to throw std::runtime_error whose message contains `needle`.
template <typename F>
void RequireThrowsMentioning(F make, const std::string& needle) {
  try {
    make();
    FAIL("expected std::runtime_error mentioning " << needle);
  } catch (const std::runtime_error& e) {
    INFO("message: " << e.what());
    CHECK(std::string(e.what()).find(needle) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("Recorder round-trips runs and splits through a reopened database", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  RunRecord first = MakeRun(0, 5);
  RunRecord second = MakeRun(1, 3);
  second.lap_time_s = std::numeric_limits<double>::quiet_NaN();  // never finished
  second.splits[1].split_s = std::numeric_limits<double>::infinity();
  second.interface.clear();
  second.view_fps = std::numeric_limits<double>::quiet_NaN();  // no view: not measured
  second.picture.clear();
  second.switches.clear();
  second.contacts.clear();
  const RunRecord third = MakeRun(2, 1);  // its truth's lap judged, not completed

  int64_t id1 = 0;
  int64_t id2 = 0;
  {
    Recorder recorder(file);
    CHECK(recorder.path() == file);
    CHECK(recorder.LoadAll().empty());
    id1 = recorder.Save(first);
    id2 = recorder.Save(second);
    recorder.Save(third);
  }
  CHECK(id1 > 0);
  CHECK(id2 > id1);

  Recorder reopened(file);
  const std::vector<RunRecord> runs = reopened.LoadAll();
  REQUIRE(runs.size() == 3);
  CHECK(runs[0].id == id1);
  CHECK(runs[1].id == id2);
  {
    INFO("first run");
    CheckSame(runs[0], first);
  }
  {
    INFO("second run");
    CheckSame(runs[1], second);
  }
  {
    INFO("third run");
    CheckSame(runs[2], third);
  }
}

TEST_CASE("Recorder stores the start time as ISO-8601 UTC and a schema version", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  {
    Recorder recorder(file);
    RunRecord run = MakeRun(0, 0);
    run.started_wall_ns = 1'714'566'896'789'000'000;  // 2024-05-01T12:34:56.789Z
    recorder.Save(run);
  }
  RawDb raw(file);
  CHECK(raw.Text("SELECT started_utc FROM runs") == "2024-05-01T12:34:56.789Z");
  CHECK(raw.Integer("PRAGMA user_version") == 16);
}

TEST_CASE("Recorder creates missing parent folders", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "a" / "b" / "c" / "runs.db";
  REQUIRE_FALSE(fs::exists(file.parent_path()));
  Recorder recorder(file);
  CHECK(fs::is_directory(file.parent_path()));
  CHECK(fs::exists(file));
  recorder.Save(MakeRun(0, 2));
  CHECK(recorder.LoadAll().size() == 1);
}

TEST_CASE("Recorder set-up errors name the database file", "[recorder]") {
  TempDir tmp;

  SECTION("parent folder cannot be created because a file is in the way") {
    const fs::path blocker = tmp.path() / "blocker";
    std::ofstream(blocker) << "not a folder\n";
    const fs::path file = blocker / "sub" / "runs.db";
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
  }

  SECTION("file is not a SQLite database") {
    const fs::path file = tmp.path() / "garbage.db";
    {
      std::ofstream out(file, std::ios::binary);
      for (int i = 0; i < 64; ++i) out << "this is not a sqlite database, just text\n";
    }
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
  }

  SECTION("schema is newer than this build understands") {
    const fs::path file = tmp.path() / "future.db";
    {
      RawDb raw(file);
      raw.Exec("PRAGMA user_version = 17");
    }
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "schema version 17");
  }

  SECTION("the path is a folder") {
    const fs::path file = tmp.path() / "folder.db";
    fs::create_directories(file);
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "is a folder");
  }

  SECTION("the path's folder is a regular file") {
    const fs::path blocker = tmp.path() / "file";
    std::ofstream(blocker) << "a file\n";
    const fs::path file = blocker / "runs.db";
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); },
                            "'" + blocker.string() + "' is a file");
  }

  SECTION("garbage is not a database") {
    const fs::path file = tmp.path() / "garbage.db";
    std::ofstream(file, std::ios::binary) << std::string(8192, '\x5a');
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "is not a SQLite database");
  }

  SECTION("another program's database is not touched") {
    const fs::path file = tmp.path() / "foreign.db";
    {
      RawDb raw(file);
      raw.Exec("CREATE TABLE invoices (id INTEGER PRIMARY KEY, amount REAL)");
    }
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "not a Haptel database");
    RawDb raw(file);
    CHECK(raw.Integer("SELECT COUNT(*) FROM sqlite_master WHERE name = 'runs'") == 0);
    CHECK(raw.Integer("PRAGMA user_version") == 0);
  }

  SECTION("a file another connection holds locked fails, after a bounded wait") {
    const fs::path file = tmp.path() / "locked.db";
    { Recorder first(file); }
    RawDb holder(file);
    holder.Exec("BEGIN EXCLUSIVE");
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "locked");
    holder.Exec("ROLLBACK");
    Recorder after(file);  // the lock gone, the file works
    CHECK(after.LoadAll().empty());
  }
}

TEST_CASE("A database whose inner pages are garbage is refused at opening, before any run",
          "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "damaged.db";
  {
    // Ten runs of 100 s paths: a file of some 250 pages, the schema on page 1.
    Recorder recorder(file);
    for (int n = 0; n < 10; ++n) {
      RunRecord run = MakeRun(n, 5);
      run.path.clear();
      for (int i = 0; i < 2000; ++i) run.path.push_back({0.05 * i, 0.001 * i, -0.002 * i, 0.5});
      recorder.Save(run);
    }
  }
  {
    Recorder intact(file);
    CHECK(intact.LoadAll().size() == 10);
  }
  haptel::test::DamageMiddlePage(file);
  // Opening reads only page 1: without the check the file would open, and
  // the run's save would meet the garbage at its end.
  RequireThrowsMentioning([&] { Recorder recorder(file); },
                          "database " + file.string() + ": is damaged");
  RequireThrowsMentioning([&] { Recorder recorder(file); }, "SQLite's quick_check");
  RequireThrowsMentioning([&] { Recorder recorder(file); }, "another --database");
}

TEST_CASE("A database deleted or replaced under an open Recorder is not written blind",
          "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  Recorder recorder(file);
  recorder.Save(MakeRun(0, 2));

  SECTION("deleted") {
    for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(file.string() + suffix);
  }
  SECTION("replaced") {
    const fs::path other = tmp.path() / "other.db";
    { Recorder fresh(other); }
    fs::rename(other, file);
  }
  // SQLite would write the run into the unlinked file, and it would be lost.
  RequireThrowsMentioning([&] { recorder.Save(MakeRun(1, 2)); }, "deleted or replaced");
  RequireThrowsMentioning([&] { recorder.Save(MakeRun(1, 2)); }, file.string());
}

TEST_CASE("A run the database did not take is written whole beside it", "[recorder]") {
  TempDir tmp;
  const fs::path db = tmp.path() / "runs.db";
  RunRecord run = MakeRun(2, 3);
  run.lap_time_s = std::numeric_limits<double>::quiet_NaN();
  run.config_name = "quote \" and\nnewline";
  const int64_t wall_ns = 1'714'566'896'789'000'000;  // 2024-05-01T12:34:56.789Z

  const fs::path file = haptel::record::WriteUnsavedRun(run, db, wall_ns);
  CHECK(file == tmp.path() / "runs.db.unsaved-20240501T123456.789Z.json");
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  CHECK(text == haptel::record::RunRecordJson(run) + "\n");
  CHECK(std::count(text.begin(), text.end(), '\n') == 1);  // one line: strings are escaped
  for (const std::string& part :
       {std::string("\"config_name\":\"quote \\\" and\\u000anewline\""),
        std::string("\"lap_time_s\":null"), std::string("\"physics_rate_short\":true"),
        std::string("\"disengaged_s\":2,\"pseudo_haptic_gain_mean\":null,\"ff_effects_played\":0"),
        // MakeRun(2)'s truth: judged, not completed.
        std::string("\"completed_truth\":false,\"lap_time_truth_s\":null,"
                    "\"lap_time_truth_projected\":false,\"gates_truth_passed\":5,"
                    "\"gates_truth_missed\":2"),
        std::string("\"counters\":{\"servo_overruns\":5,\"servo_forces_clamped\":0,"
                    "\"video_frames_dropped\":1099511627776}"),
        std::string("\"splits\":[{\"gate\":0,"), std::string("\"switches\":[{\"t_s\":3.25,"),
        std::string("\"contacts\":[{\"t_s\":0.34999999999999998,"),
        std::string("\"started_wall_ns\":") + std::to_string(run.started_wall_ns)}) {
    INFO(part);
    CHECK(text.find(part) != std::string::npos);
  }
  CHECK(text.find("\"path\":[{\"t_s\":0,\"x\":-0.33333333333333331,") != std::string::npos);

  // Never overwritten: a second run in the same millisecond gets a name of its own.
  const fs::path second = haptel::record::WriteUnsavedRun(MakeRun(3, 1), db, wall_ns);
  CHECK(second == tmp.path() / "runs.db.unsaved-20240501T123456.789Z-2.json");
  CHECK(fs::file_size(file) == text.size());

  // A database folder that is gone: the system's temporary folder takes it.
  const std::string name = tmp.path().filename().string() + ".db";  // unique to this test
  const fs::path elsewhere =
      haptel::record::WriteUnsavedRun(run, tmp.path() / "gone" / name, wall_ns + 1'000'000);
  CHECK(elsewhere.parent_path() == fs::temp_directory_path());
  CHECK(elsewhere.filename() == name + ".unsaved-20240501T123456.790Z.json");
  CHECK(fs::file_size(elsewhere) == text.size());
  fs::remove(elsewhere);
}

TEST_CASE("A study's run kept in a file says whose trial it was, first", "[recorder]") {
  TempDir tmp;
  const RunRecord run = MakeRun(2, 3);
  const fs::path file = haptel::record::WriteUnsavedRun(
      run, tmp.path() / "study.db", 1'714'566'896'789'000'000,
      haptel::record::TrialOfRun{"lab \"A\"", "P7", 3, "gesture", 2});
  std::ifstream in(file);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // The trial, then the run whole, as without it.
  CHECK(text ==
        "{\"trial\":{\"study\":\"lab \\\"A\\\"\",\"participant\":\"P7\",\"position\":3,"
        "\"condition\":\"gesture\",\"repetition\":2}," +
            haptel::record::RunRecordJson(run).substr(1) + "\n");
}

TEST_CASE("A failing Save rolls back and leaves the Recorder usable", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  Recorder recorder(file);
  const RunRecord good = MakeRun(0, 5);
  recorder.Save(good);
  REQUIRE(recorder.LoadAll().size() == 1);

  RunRecord bad = MakeRun(1, 4);
  bad.config_name = "bad";
  bad.splits[3].gate = bad.splits[1].gate;  // duplicate (run_id, gate): primary key violation
  RequireThrowsMentioning([&] { recorder.Save(bad); }, file.string());

  std::vector<RunRecord> runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);
  CheckSame(runs[0], good);
  {
    RawDb raw(file);
    CHECK(raw.Integer("SELECT COUNT(*) FROM runs WHERE config_name = 'bad'") == 0);
    CHECK(raw.Integer("SELECT COUNT(*) FROM gate_splits") == 5);  // no splits of the bad run
  }

  const RunRecord after = MakeRun(2, 3);
  const int64_t id = recorder.Save(after);
  runs = recorder.LoadAll();
  REQUIRE(runs.size() == 2);
  CHECK(runs[1].id == id);
  CheckSame(runs[1], after);
}

TEST_CASE("Recorder round-trips a 10-minute path and sets a saved run's picture", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  RunRecord run = MakeRun(3, 5);
  run.path.clear();
  for (int i = 0; i < 12'000; ++i) {  // one point every 0.05 s for 600 s
    run.path.push_back({0.05 * i, std::sin(i * 1e-3), std::cos(i * 1e-3) * 2.5, 0.001 * i});
  }
  run.picture.clear();
  int64_t id = 0;
  {
    Recorder recorder(file);
    id = recorder.Save(run);
    recorder.Save(MakeRun(4, 2));  // a second run: children must not mix
    const fs::path png = tmp.path() / "pictures" / "run-1.png";
    recorder.SetPicture(id, png);
    run.picture = png.string();
    RequireThrowsMentioning([&] { recorder.SetPicture(id + 100, png); }, "no such run");
  }
  Recorder reopened(file);
  const std::vector<RunRecord> runs = reopened.LoadAll();
  REQUIRE(runs.size() == 2);
  CHECK(runs[0].id == id);
  CheckSame(runs[0], run);
  CheckSame(runs[1], MakeRun(4, 2));
  RawDb raw(file);
  CHECK(raw.Integer("SELECT COUNT(*) FROM run_path") == 12'000 + 24);
}

namespace {

// Schema v1 exactly as recorder.cpp created it (git show acd77c8:mediator/src/recorder.cpp).
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE IF NOT EXISTS runs (
  id INTEGER PRIMARY KEY,
  started_utc TEXT NOT NULL,
  started_wall_ns INTEGER NOT NULL,
  config_name TEXT NOT NULL,
  track TEXT NOT NULL,
  interface TEXT NOT NULL,
  vehicle TEXT NOT NULL,
  completed INTEGER NOT NULL,
  outcome TEXT NOT NULL,
  lap_time_s REAL,
  gates_passed INTEGER NOT NULL,
  gates_total INTEGER NOT NULL,
  gates_missed INTEGER NOT NULL,
  obstacles_touched INTEGER NOT NULL,
  vehicle_pid INTEGER NOT NULL,
  servo_rate_hz REAL,
  servo_period_p99_us REAL,
  command_rtt_ms_p50 REAL,
  command_rtt_ms_p99 REAL,
  video_frames INTEGER NOT NULL,
  video_fps REAL,
  video_latency_ms_p50 REAL
);
CREATE TABLE IF NOT EXISTS gate_splits (
  run_id INTEGER NOT NULL REFERENCES runs(id),
  gate INTEGER NOT NULL,
  passed INTEGER NOT NULL,
  split_s REAL,
  PRIMARY KEY (run_id, gate)
);
PRAGMA user_version = 1;
INSERT INTO runs (started_utc, started_wall_ns, config_name, track, interface, vehicle,
                  completed, outcome, lap_time_s, gates_passed, gates_total, gates_missed,
                  obstacles_touched, vehicle_pid, servo_rate_hz, servo_period_p99_us,
                  command_rtt_ms_p50, command_rtt_ms_p99, video_frames, video_fps,
                  video_latency_ms_p50)
VALUES ('2024-05-01T12:34:56.789Z', 1714566896789000000, 'v1 run', 'grand-prix', 'gesture',
        'tank-sim', 1, 'completed', 101.5, 5, 5, 0, 2, 4321, 999.0, 1040.0, 1.25, 6.5, 3000,
        29.5, 80.0);
INSERT INTO gate_splits (run_id, gate, passed, split_s) VALUES (1, 0, 1, 20.0), (1, 1, 0, 41.5);
)sql";

/// The v1 run above, as the current Recorder loads it: v2's text empty, v2's
/// and v3's metrics NaN (not measured), v3's flags false, no switches, path,
/// contacts or counters.
RunRecord V1Run() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  RunRecord run;
  run.started_wall_ns = 1714566896789000000;
  run.config_name = "v1 run";
  run.track = "grand-prix";
  run.interface = "gesture";
  run.vehicle = "tank-sim";
  run.completed = true;
  run.outcome = "completed";
  run.lap_time_s = 101.5;
  run.gates_passed = 5;
  run.gates_total = 5;
  run.gates_missed = 0;
  run.obstacles_touched = 2;
  run.vehicle_pid = 4321;
  run.servo_rate_hz = 999.0;
  run.servo_period_p99_us = 1040.0;
  run.command_rtt_ms_p50 = 1.25;
  run.command_rtt_ms_p99 = 6.5;
  run.video_frames = 3000;
  run.video_fps = 29.5;
  run.video_latency_ms_p50 = 80.0;
  run.distance_m = nan;
  run.view_fps = nan;
  run.view_frame_p99_ms = nan;
  run.video_to_screen_ms_p50 = nan;
  run.video_to_screen_ms_p99 = nan;
  run.servo_target_hz = nan;
  run.physics_rate_hz = nan;
  run.physics_target_hz = nan;
  run.disengaged_s = nan;      // v13's: not recorded (NULL)
  run.ff_effects_played = -1;  // v13's: not recorded (NULL)
  run.splits = {{0, true, 20.0}, {1, false, 41.5}};
  return run;
}

}  // namespace

TEST_CASE("A v1 database is migrated to the current schema in place and keeps its runs",
          "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "v1.db";
  {
    RawDb raw(file);
    raw.Exec(kSchemaV1);
    REQUIRE(raw.Integer("PRAGMA user_version") == 1);
  }

  const RunRecord fresh = MakeRun(5, 3);
  {
    Recorder recorder(file);
    std::vector<RunRecord> runs = recorder.LoadAll();
    REQUIRE(runs.size() == 1);
    CHECK(runs[0].id == 1);
    CheckSame(runs[0], V1Run());

    const int64_t id = recorder.Save(fresh);
    CHECK(id == 2);
    runs = recorder.LoadAll();
    REQUIRE(runs.size() == 2);
    CheckSame(runs[0], V1Run());
    CheckSame(runs[1], fresh);
  }

  RawDb raw(file);
  CHECK(raw.Integer("PRAGMA user_version") == 16);
  CHECK(raw.Text("PRAGMA integrity_check") == "ok");
  CHECK(raw.Integer("SELECT COUNT(*) FROM pragma_foreign_key_check") == 0);
  for (const char* table : {"interface_switches", "run_path", "run_contacts", "run_counters"}) {
    INFO(table);
    const std::string count_fk = std::string("SELECT COUNT(*) FROM pragma_foreign_key_list('") +
                                 table + "') WHERE \"table\" = 'runs' AND \"from\" = 'run_id'";
    CHECK(raw.Integer(count_fk.c_str()) == 1);
    const std::string count_index =
        std::string("SELECT COUNT(*) FROM pragma_index_list('") + table +
        "') AS l JOIN pragma_index_info(l.name) AS i WHERE i.name = 'run_id'";
    CHECK(raw.Integer(count_index.c_str()) == 1);
  }
  // Reopening a current database changes nothing.
  {
    Recorder again(file);
    CHECK(again.LoadAll().size() == 2);
  }
  CHECK(raw.Integer("PRAGMA user_version") == 16);
}

namespace {

// Schema v2's step exactly as recorder.cpp ran it (git show e149374:mediator/src/recorder.cpp),
// and a v2 run with a switch, a path point and a contact.
constexpr const char* kSchemaV2 = R"sql(
ALTER TABLE runs ADD COLUMN operator_kind TEXT NOT NULL DEFAULT '';
ALTER TABLE runs ADD COLUMN device TEXT NOT NULL DEFAULT '';
ALTER TABLE runs ADD COLUMN distance_m REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN view_fps REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN view_frame_p99_ms REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN video_to_screen_ms_p50 REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN video_to_screen_ms_p99 REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN picture TEXT NOT NULL DEFAULT '';
CREATE TABLE interface_switches (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  from_interface TEXT NOT NULL,
  to_interface TEXT NOT NULL
);
CREATE INDEX interface_switches_run_id ON interface_switches(run_id);
CREATE TABLE run_path (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  x REAL NOT NULL,
  y REAL NOT NULL,
  speed_mps REAL NOT NULL
);
CREATE INDEX run_path_run_id ON run_path(run_id);
CREATE TABLE run_contacts (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  x REAL NOT NULL,
  y REAL NOT NULL
);
CREATE INDEX run_contacts_run_id ON run_contacts(run_id);
PRAGMA user_version = 2;
UPDATE runs SET operator_kind = 'auto', device = 'sim', distance_m = 12.5, view_fps = 60.0,
                view_frame_p99_ms = 4.0, video_to_screen_ms_p50 = 50.0,
                video_to_screen_ms_p99 = 70.0, picture = '/runs/pictures/run-1.png';
INSERT INTO interface_switches VALUES (1, 2.5, 'gesture', 'cockpit');
INSERT INTO run_path VALUES (1, 0.05, 1.0, 2.0, 0.5);
INSERT INTO run_contacts VALUES (1, 0.75, 1.5, 2.5);
)sql";

RunRecord V2Run() {
  RunRecord run = V1Run();
  run.operator_kind = "auto";
  run.device = "sim";
  run.distance_m = 12.5;
  run.view_fps = 60.0;
  run.view_frame_p99_ms = 4.0;
  run.video_to_screen_ms_p50 = 50.0;
  run.video_to_screen_ms_p99 = 70.0;
  run.picture = "/runs/pictures/run-1.png";
  run.switches = {{2.5, "gesture", "cockpit"}};
  run.path = {{0.05, 1.0, 2.0, 0.5}};
  run.contacts = {{0.75, 1.5, 2.5}};
  return run;
}

}  // namespace

TEST_CASE("A v2 database is migrated to v3: its runs keep everything, new runs keep counters",
          "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "v2.db";
  {
    RawDb raw(file);
    raw.Exec(kSchemaV1);
    raw.Exec(kSchemaV2);
    REQUIRE(raw.Integer("PRAGMA user_version") == 2);
  }
  const RunRecord fresh = MakeRun(6, 2);
  {
    Recorder recorder(file);
    std::vector<RunRecord> runs = recorder.LoadAll();
    REQUIRE(runs.size() == 1);
    CheckSame(runs[0], V2Run());
    recorder.Save(fresh);
  }
  Recorder reopened(file);
  const std::vector<RunRecord> runs = reopened.LoadAll();
  REQUIRE(runs.size() == 2);
  CheckSame(runs[0], V2Run());
  CheckSame(runs[1], fresh);
  RawDb raw(file);
  CHECK(raw.Integer("PRAGMA user_version") == 16);
  CHECK(raw.Text("PRAGMA integrity_check") == "ok");
  CHECK(raw.Integer(
            "SELECT value FROM run_counters WHERE run_id = 2 AND name = 'servo_overruns'") == 9);
  // The v2 run has no flags (NULL); the new one has its own.
  CHECK(raw.Integer("SELECT COUNT(*) FROM runs WHERE servo_rate_short IS NULL") == 1);
}

TEST_CASE("A migration that fails leaves the v1 database as it was", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "v1.db";
  {
    RawDb raw(file);
    raw.Exec(kSchemaV1);
    raw.Exec("CREATE TABLE run_path (something_else TEXT)");  // in v2's way
  }
  RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
  RequireThrowsMentioning([&] { Recorder recorder(file); }, "migrate schema to version 2");
  RawDb raw(file);
  CHECK(raw.Integer("PRAGMA user_version") == 1);
  CHECK(raw.Integer("SELECT COUNT(*) FROM pragma_table_info('runs') WHERE name = 'picture'") == 0);
  CHECK(raw.Integer("SELECT COUNT(*) FROM sqlite_master WHERE name = 'run_contacts'") == 0);
  CHECK(raw.Integer("SELECT COUNT(*) FROM runs") == 1);
}

TEST_CASE("A save failing at the path's end leaves no part of the run", "[recorder]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  Recorder recorder(file);
  const RunRecord good = MakeRun(0, 5);
  recorder.Save(good);

  RunRecord bad = MakeRun(1, 5);
  bad.config_name = "bad";
  bad.path.clear();
  for (int i = 0; i < 12'000; ++i) bad.path.push_back({0.05 * i, 0.001 * i, 0.0, 0.5});
  bad.path[11'999].x = std::numeric_limits<double>::quiet_NaN();  // NOT NULL: the last row fails
  RequireThrowsMentioning([&] { recorder.Save(bad); }, file.string());
  RequireThrowsMentioning([&] { recorder.Save(bad); }, "path point 11999");

  bad.path[11'999].x = 1.0;
  bad.contacts[1].t_s = std::numeric_limits<double>::quiet_NaN();
  RequireThrowsMentioning([&] { recorder.Save(bad); }, "contact 1");

  {
    RawDb raw(file);
    CHECK(raw.Integer("SELECT COUNT(*) FROM runs") == 1);
    CHECK(raw.Integer("SELECT COUNT(*) FROM gate_splits") == 5);
    CHECK(raw.Integer("SELECT COUNT(*) FROM interface_switches") ==
          static_cast<int64_t>(good.switches.size()));
    CHECK(raw.Integer("SELECT COUNT(*) FROM run_path") == static_cast<int64_t>(good.path.size()));
    CHECK(raw.Integer("SELECT COUNT(*) FROM run_contacts") ==
          static_cast<int64_t>(good.contacts.size()));
  }
  std::vector<RunRecord> runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);
  CheckSame(runs[0], good);

  bad.contacts[1].t_s = 2.0;
  const int64_t id = recorder.Save(bad);
  runs = recorder.LoadAll();
  REQUIRE(runs.size() == 2);
  CHECK(runs[1].id == id);
  CheckSame(runs[1], bad);
}

TEST_CASE("A writer killed mid-transaction leaves no trace and no lock", "[recorder][fork]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  const RunRecord before = MakeRun(0, 5);
  {
    Recorder recorder(file);  // closed before fork: no SQLite handle crosses it
    recorder.Save(before);
  }

  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    // Child: the same kind of write Save does, then die without committing.
    // A tiny page cache makes SQLite spill uncommitted pages into the WAL, so
    // the file really holds a half-written transaction when we die.
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) _exit(10);
    sqlite3_busy_timeout(db, 2000);
    auto exec = [db](const char* sql) {
      if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) != SQLITE_OK) _exit(11);
    };
    exec("PRAGMA cache_size = 10");
    exec("BEGIN IMMEDIATE");
    exec(
        "INSERT INTO runs (started_utc, started_wall_ns, config_name, track, interface, vehicle,"
        " completed, outcome, lap_time_s, gates_passed, gates_total, gates_missed,"
        " obstacles_touched, vehicle_pid, servo_rate_hz, servo_period_p99_us,"
        " command_rtt_ms_p50, command_rtt_ms_p99, video_frames, video_fps,"
        " video_latency_ms_p50) VALUES ('1970-01-01T00:00:00.000Z', 0, 'child', 't', 'i', 'v',"
        " 1, 'completed', 1.0, 5, 5, 0, 0, 1, 1000.0, 1.0, 1.0, 1.0, 1, 30.0, 1.0)");
    exec(
        "WITH RECURSIVE g(n) AS (SELECT 0 UNION ALL SELECT n + 1 FROM g WHERE n < 19999)"
        " INSERT INTO gate_splits (run_id, gate, passed, split_s)"
        " SELECT (SELECT MAX(id) FROM runs), n, 1, n * 0.5 FROM g");
    ::raise(SIGKILL);
    _exit(12);  // not reached
  }
  ChildGuard child(pid);
  const int status = child.Wait(60.0);
  INFO("child wait status " << status);
  REQUIRE(status != ChildGuard::kStillRunning);
  REQUIRE(WIFSIGNALED(status));
  REQUIRE(WTERMSIG(status) == SIGKILL);

  Recorder recorder(file);
  std::vector<RunRecord> runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);  // only the run saved before the fork
  CheckSame(runs[0], before);
  {
    RawDb raw(file);
    CHECK(raw.Integer("SELECT COUNT(*) FROM runs WHERE config_name = 'child'") == 0);
    CHECK(raw.Integer("SELECT COUNT(*) FROM gate_splits") == 5);
    CHECK(raw.Text("PRAGMA integrity_check") == "ok");
  }

  // No stale lock: a new write goes through.
  const RunRecord after = MakeRun(1, 2);
  const int64_t id = recorder.Save(after);
  runs = recorder.LoadAll();
  REQUIRE(runs.size() == 2);
  CHECK(runs[1].id == id);
  CheckSame(runs[1], after);
}

TEST_CASE("Saves killed at an arbitrary point leave only whole runs", "[recorder][fork]") {
  TempDir tmp;
  const fs::path file = tmp.path() / "runs.db";
  constexpr int kSplitsPerRun = 5;
  const RunRecord before = MakeRun(0, kSplitsPerRun);
  {
    Recorder recorder(file);
    recorder.Save(before);
  }

  // Several kills at different points of the child's save loop. The delays
  // only vary where the kill lands; nothing is asserted about time.
  size_t saved_by_children = 0;
  for (const int delay_ms : {15, 40, 90}) {
    INFO("kill after " << delay_ms << " ms");
    int ready[2];
    REQUIRE(::pipe(ready) == 0);
    const pid_t pid = ::fork();
    REQUIRE(pid >= 0);
    if (pid == 0) {
      ::close(ready[0]);
      try {
        Recorder recorder(file);
        for (int i = 1; i <= 1'000'000; ++i) {
          RunRecord run = MakeRun(i, kSplitsPerRun);
          run.config_name = "child-loop";
          recorder.Save(run);
          if (i == 1) {
            const char byte = 1;
            if (::write(ready[1], &byte, 1) != 1) _exit(20);
          }
        }
      } catch (...) {
        _exit(21);
      }
      _exit(0);
    }
    ChildGuard child(pid);
    ::close(ready[1]);
    char byte = 0;
    pollfd first_commit{ready[0], POLLIN, 0};  // a child that hangs before it must not hang us
    const bool readable = ::poll(&first_commit, 1, 60'000) == 1;
    const ssize_t got = readable ? ::read(ready[0], &byte, 1) : 0;
    ::close(ready[0]);
    REQUIRE(got == 1);  // the child committed at least one run
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    REQUIRE(::kill(child.pid(), SIGKILL) == 0);
    const int status = child.Wait(60.0);
    INFO("child wait status " << status);
    REQUIRE(status != ChildGuard::kStillRunning);
    CHECK((WIFSIGNALED(status) || (WIFEXITED(status) && WEXITSTATUS(status) == 0)));

    Recorder recorder(file);
    const std::vector<RunRecord> runs = recorder.LoadAll();
    REQUIRE(runs.size() >= 2 + saved_by_children);
    CheckSame(runs[0], before);
    size_t children = 0;
    for (const RunRecord& run : runs) {
      if (run.config_name != "child-loop") continue;
      ++children;
      INFO("run id " << run.id);
      REQUIRE(run.splits.size() == static_cast<size_t>(kSplitsPerRun));
      for (int g = 0; g < kSplitsPerRun; ++g) CHECK(run.splits[g].gate == g);
    }
    CHECK(children >= saved_by_children + 1);
    saved_by_children = children;

    RawDb raw(file);
    CHECK(raw.Integer("SELECT COUNT(*) FROM gate_splits") ==
          static_cast<int64_t>(runs.size() * kSplitsPerRun));
    CHECK(raw.Text("PRAGMA integrity_check") == "ok");
  }

  // No stale lock after the last kill.
  Recorder recorder(file);
  const int64_t id = recorder.Save(MakeRun(7, kSplitsPerRun));
  const std::vector<RunRecord> runs = recorder.LoadAll();
  REQUIRE_FALSE(runs.empty());
  CHECK(runs.back().id == id);
  CHECK(runs.back().splits.size() == static_cast<size_t>(kSplitsPerRun));
}
