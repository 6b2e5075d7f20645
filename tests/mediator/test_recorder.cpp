// Tests for haptel::mediator::Recorder: round trip, folder creation, errors
// naming the file, rollback of a failing save, and that a process killed in the
// middle of a write leaves no half-written run behind.
#include <signal.h>
#include <sqlite3.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "haptel/mediator/recorder.hpp"

namespace fs = std::filesystem;
using haptel::mediator::GateSplit;
using haptel::mediator::Recorder;
using haptel::mediator::RunRecord;

namespace {

/// A fresh, uniquely named folder under $HAPTEL_TEST_TMP (or the system temp
/// folder), removed with everything in it at scope exit.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    const char* env = std::getenv("HAPTEL_TEST_TMP");
    const fs::path base = (env != nullptr && *env != '\0') ? fs::path(env)
                                                           : fs::temp_directory_path();
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
  explicit ChildGuard(pid_t pid) : pid_(pid) {}
  ~ChildGuard() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  ChildGuard(const ChildGuard&) = delete;
  ChildGuard& operator=(const ChildGuard&) = delete;

  /// Waits for the child and returns its wait status.
  int Wait() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
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
  for (int g = 0; g < split_count; ++g) {
    GateSplit split;
    split.gate = g;
    split.passed = (g + n) % 3 != 0;
    split.split_s = split.passed ? 12.5 * (g + 1) + 0.001 * n : -1.0;
    run.splits.push_back(split);
  }
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
  REQUIRE(got.splits.size() == want.splits.size());
  for (size_t i = 0; i < want.splits.size(); ++i) {
    CHECK(got.splits[i].gate == want.splits[i].gate);
    CHECK(got.splits[i].passed == want.splits[i].passed);
    CHECK(SameReal(got.splits[i].split_s, want.splits[i].split_s));
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

  int64_t id1 = 0;
  int64_t id2 = 0;
  {
    Recorder recorder(file);
    CHECK(recorder.path() == file);
    CHECK(recorder.LoadAll().empty());
    id1 = recorder.Save(first);
    id2 = recorder.Save(second);
  }
  CHECK(id1 > 0);
  CHECK(id2 > id1);

  Recorder reopened(file);
  const std::vector<RunRecord> runs = reopened.LoadAll();
  REQUIRE(runs.size() == 2);
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
  CHECK(raw.Integer("PRAGMA user_version") == 1);
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
      raw.Exec("PRAGMA user_version = 7");
    }
    RequireThrowsMentioning([&] { Recorder recorder(file); }, file.string());
    RequireThrowsMentioning([&] { Recorder recorder(file); }, "schema version 7");
  }
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
  const int status = child.Wait();
  INFO("child wait status " << status);
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
    const ssize_t got = ::read(ready[0], &byte, 1);
    ::close(ready[0]);
    REQUIRE(got == 1);  // the child committed at least one run
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    REQUIRE(::kill(child.pid(), SIGKILL) == 0);
    const int status = child.Wait();
    INFO("child wait status " << status);
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
