// End to end, nothing measured is lost: a database that cannot work stops
// `haptel run` before the vehicle or the device starts; a save that fails at
// the end still prints the results and keeps them in a file beside the
// database; every counter reaches the JSON line and the database; and a
// physics loop that cannot keep its rate says so.
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "child.hpp"
#include "haptel/record/recorder.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;
namespace fs = std::filesystem;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

int Lines(const std::string& text) {
  return static_cast<int>(std::count(text.begin(), text.end(), '\n'));
}

std::string Read(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// Every counter name the JSON line and the database carry (docs/results.md, "The JSON line").
const std::vector<std::string> kCounters{"servo_overruns",
                                         "servo_device_lost_ticks",
                                         "servo_no_data_ticks",
                                         "servo_write_failures",
                                         "servo_forces_non_finite",
                                         "servo_forces_clamped",
                                         "servo_forces_rate_limited",
                                         "servo_setpoint_stale_ticks",
                                         "servo_setpoint_read_fallbacks",
                                         "servo_passivity_ticks",
                                         "servo_passivity_left_mj",
                                         "servo_passivity_right_mj",
                                         "servo_passivity_alpha_max_mns_m",
                                         "servo_passivity_link_ticks",
                                         "servo_passivity_device_ticks",
                                         "servo_passivity_device_mj",
                                         "servo_passivity_device_alpha_max_mns_m",
                                         "physics_overruns",
                                         "physics_hand_resets",
                                         "physics_body_resets",
                                         "physics_invalid_samples",
                                         "vehicle_watchdog_trips",
                                         "vehicle_commands_dropped",
                                         "vehicle_video_feedback_refused",
                                         "link_states_missed",
                                         "link_queue_dropped",
                                         "link_queue_dropped_bytes",
                                         "video_frames_dropped",
                                         "video_decode_failures",
                                         "video_frames_lost",
                                         "video_frames_skipped",
                                         "video_key_frame_requests",
                                         "view_record_dropped"};

/// A raw SQLite connection the test holds (for a lock, or a foreign schema).
struct RawDb {
  explicit RawDb(const fs::path& file) {
    REQUIRE(sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                            nullptr) == SQLITE_OK);
  }
  ~RawDb() { sqlite3_close_v2(db); }
  RawDb(const RawDb&) = delete;
  RawDb& operator=(const RawDb&) = delete;
  void Exec(const char* sql) {
    INFO(sql);
    REQUIRE(sqlite3_exec(db, sql, nullptr, nullptr, nullptr) == SQLITE_OK);
  }
  sqlite3* db = nullptr;
};

/// `haptel run` on the short track against `db`; progress lines on, so a
/// vehicle that started would say so.
std::vector<std::string> Run(const fs::path& db, int salt) {
  return {Bin("haptel"),
          "run",
          "--track",
          "config/tracks/test-short.yaml",
          "--json",
          "--view",
          "none",
          "--domain",
          std::to_string(test::UniqueDomain(salt)),
          "--database",
          db.string(),
          "--vehicle-timeout",
          "5",
          "--reality",
          "none"};
}

/// The database is refused before anything starts: exit 2, one line naming
/// the file and `what`, no vehicle, no JSON line.
void RequireRefusedBeforeStart(const fs::path& db, const std::string& what, int salt) {
  Child c(Run(db, salt));
  const int code = c.Wait(60.0);
  INFO("stdout:\n" << c.out() << "\nstderr:\n" << c.err());
  CHECK(code == 2);
  CHECK(c.err().find(db.string()) != std::string::npos);
  CHECK(c.err().find(what) != std::string::npos);
  CHECK(Lines(c.err()) == 1);
  CHECK(c.err().find("started, pid") == std::string::npos);  // no vehicle was spawned
  CHECK(c.err().find("servo loop") == std::string::npos);    // nor the device's loop started
  CHECK(c.out().empty());                                    // no summary, no JSON line
}

}  // namespace

TEST_CASE("a database that cannot work stops haptel run before the vehicle starts, exit 2") {
  const auto dir = test::ScratchDir("e2e-db-bad");
  SECTION("a folder") {
    const auto db = dir / "folder.db";
    fs::create_directories(db);
    RequireRefusedBeforeStart(db, "is a folder", 31);
  }
  SECTION("a path under a regular file (read-only bits do not stop root; this does)") {
    const auto file = dir / "file";
    std::ofstream(file) << "a file\n";
    RequireRefusedBeforeStart(file / "runs.db", file.string() + "' is a file", 32);
  }
  SECTION("a corrupt file") {
    const auto db = dir / "corrupt.db";
    std::ofstream(db, std::ios::binary) << std::string(16384, '\x5a');
    RequireRefusedBeforeStart(db, "is not a SQLite database", 33);
  }
  SECTION("a real database whose inner pages are garbage") {
    const auto db = dir / "damaged.db";
    {
      record::Recorder recorder(db);
      record::RunRecord run;
      run.config_name = "a lap";
      for (int i = 0; i < 2000; ++i) run.path.push_back({0.05 * i, 0.001 * i, 0.0, 0.5});
      for (int n = 0; n < 10; ++n) recorder.Save(run);
    }
    test::DamageMiddlePage(db);
    RequireRefusedBeforeStart(db, "is damaged", 39);
  }
  SECTION("a file another connection holds locked") {
    const auto db = dir / "locked.db";
    { record::Recorder first(db); }
    RawDb holder(db);
    holder.Exec("BEGIN EXCLUSIVE");
    RequireRefusedBeforeStart(db, "locked", 34);
    holder.Exec("ROLLBACK");
  }
  SECTION("a newer schema") {
    const auto db = dir / "future.db";
    {
      RawDb raw(db);
      raw.Exec("PRAGMA user_version = 99");
    }
    RequireRefusedBeforeStart(db, "schema version 99 is newer", 35);
  }
  SECTION("another program's database") {
    const auto db = dir / "foreign.db";
    {
      RawDb raw(db);
      raw.Exec("CREATE TABLE invoices (id INTEGER PRIMARY KEY)");
    }
    RequireRefusedBeforeStart(db, "not a Haptel database", 36);
  }
}

TEST_CASE(
    "a database deleted during the run: summary and JSON still printed, results in a file beside "
    "it, exit 4") {
  const auto dir = test::ScratchDir("e2e-db-lost");
  const auto db = dir / "runs.db";
  Child haptel(Run(db, 37));
  REQUIRE(test::WaitFor(
      [&] {
        haptel.Pump();
        return haptel.err().find(" lap ") !=
               std::string::npos;  // the first progress line: under way
      },
      90.0));
  REQUIRE(fs::exists(db));  // opened and checked before the run
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(db.string() + suffix);

  const int code = haptel.Wait(120.0);
  INFO("stdout:\n" << haptel.out() << "\nstderr:\n" << haptel.err());
  CHECK(code == 4);
  const std::string json = haptel.LastLine();
  REQUIRE(json.front() == '{');
  CHECK(JsonField(json, "completed") == "true");
  CHECK(JsonField(json, "recorded") == "false");
  CHECK(JsonField(json, "run_id") == "0");
  CHECK(haptel.out().find("NOT recorded") != std::string::npos);
  const fs::path unsaved = JsonField(json, "unsaved_file");
  CHECK(unsaved.parent_path() == dir);
  CHECK(unsaved.filename().string().rfind("runs.db.unsaved-", 0) == 0);
  CHECK(haptel.err().find("run not recorded") != std::string::npos);
  CHECK(haptel.err().find(unsaved.string()) != std::string::npos);  // the message names the file
  CHECK(haptel.err().find("deleted or replaced") != std::string::npos);

  // The whole run is in it: the figures, the splits, the path, the counters.
  const std::string kept = Read(unsaved);
  CHECK(JsonField(kept, "outcome") == "completed");
  CHECK(JsonField(kept, "lap_time_s") == JsonField(kept, "lap_time_s"));
  CHECK(kept.find("\"splits\":[{\"gate\":0,\"passed\":true") != std::string::npos);
  CHECK(kept.find("\"path\":[{\"t_s\":") != std::string::npos);
  CHECK(kept.find("\"counters\":{\"servo_overruns\":") != std::string::npos);
  // And every counter reached the JSON line.
  for (const std::string& name : kCounters) {
    INFO(name);
    CHECK(!JsonField(json, name).empty());
    CHECK(kept.find("\"" + name + "\":") != std::string::npos);
  }
}

TEST_CASE(
    "a physics loop far too slow for its step says so in the progress line, the JSON and the "
    "database") {
  const auto dir = test::ScratchDir("e2e-rate");
  const auto db = dir / "runs.db";
  const fs::path config = fs::absolute("config");
  // 10 kHz with 1000 solver iterations, and a pile of 216 boxes pressed
  // into each other so none falls asleep: no machine steps that in time.
  std::ofstream(dir / "physics.yaml") << "step_s: 0.0001\nsolver_iterations: 1000\n";
  {
    std::ofstream scene(dir / "pile.yaml");
    scene << "objects:\n  - name: floor\n    type: static\n    shapes:\n      - {type: plane, "
             "normal: [0, 0, 1], offset: 0}\n";
    for (int i = 0; i < 216; ++i) {
      scene << "  - name: box" << i << "\n    type: dynamic\n    mass: 0.1\n    position: ["
            << 0.3 + 0.045 * (i % 6) << ", " << 0.045 * (i / 6 % 6) << ", "
            << 0.03 + 0.045 * (i / 36) << "]\n"
            << "    shapes:\n      - {type: box, size: [0.05, 0.05, 0.05]}\n";
    }
  }
  std::ofstream(dir / "run.yaml") << "name: heavy\ntrack: "
                                  << (config / "tracks/test-short.yaml").string()
                                  << "\nvehicle: " << (config / "vehicles/sim-robot.yaml").string()
                                  << "\ndevice: " << (config / "devices/sim.yaml").string()
                                  << "\ninterfaces_dir: " << (config / "interfaces").string()
                                  << "\nphysics: physics.yaml\nscene: pile.yaml\n";
  Child haptel({Bin("haptel"), "run", "--config", (dir / "run.yaml").string(), "--interface",
                "gesture", "--json", "--view", "none", "--time-limit", "5", "--domain",
                std::to_string(test::UniqueDomain(38)), "--database", db.string(),
                "--vehicle-timeout", "5"});
  const int code = haptel.Wait(120.0);
  INFO("stdout:\n" << haptel.out() << "\nstderr:\n" << haptel.err());
  REQUIRE(code == 1);  // the time limit: not completed
  const std::string json = haptel.LastLine();
  REQUIRE(json.front() == '{');
  CHECK(JsonField(json, "outcome") == "time limit");
  CHECK(JsonField(json, "scene_bodies") == "217");
  CHECK(JsonField(json, "physics_target_hz") == "10000");
  CHECK(JsonField(json, "physics_rate_short") == "true");
  CHECK(haptel.err().find("Hz of 10000 Hz: cannot keep its rate") != std::string::npos);
  CHECK(haptel.err().find("physics ") != std::string::npos);
  CHECK(haptel.out().find("CANNOT KEEP ITS RATE") != std::string::npos);

  record::Recorder recorder(db);
  const auto runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);
  CHECK(runs[0].physics_rate_short);
  CHECK(runs[0].physics_target_hz == Approx(10000.0));
  CHECK(runs[0].physics_rate_hz > 0.0);
  CHECK(runs[0].servo_target_hz == Approx(1000.0));
  REQUIRE(runs[0].counters.size() == kCounters.size());
  for (size_t i = 0; i < kCounters.size(); ++i) {
    CHECK(runs[0].counters[i].name == kCounters[i]);
    CHECK(std::to_string(runs[0].counters[i].value) == JsonField(json, kCounters[i]));
  }
}
