// End to end through the CAN code path: `haptel run` drives the simulated CAN
// robot (the real adapter, a socket pair, emulated ODrives and I/O node) and
// the run's candump log shows the velocity commands and both heartbeats, and
// the JSON line names it; a log on a full disk is said and fails the run
// (exit 5); the real robot's adapter on a kernel without CAN support is a
// one-line set-up error.
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>

#include "child.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/vehicles/can_bus.hpp"
#include "haptel/vehicles/candump_log.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;

namespace {
std::string CanBin(const std::string& name) { return (test::BinDir() / name).string(); }

/// The shipped can-robot-sim.yaml in `dir`, its log in `dir`/can.
std::filesystem::path CanVehicleFile(const std::filesystem::path& dir) {
  std::string text;
  {
    std::ifstream in("config/vehicles/can-robot-sim.yaml");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::string shipped_log = "log_dir: ../../runs/can";
  REQUIRE(text.find(shipped_log) != std::string::npos);
  text.replace(text.find(shipped_log), shipped_log.size(), "log_dir: " + (dir / "can").string());
  text.replace(text.find("world: ../tracks/"), 17,
               "world: " + (std::filesystem::current_path() / "config/tracks/").string());
  const auto vehicle = dir / "can-robot-sim.yaml";
  std::ofstream(vehicle) << text;
  return vehicle;
}

/// The JSON line's "can_log" value: {…} or null.
std::string CanLogOf(const std::string& json) {
  const std::string key = "\"can_log\":";
  const size_t at = json.find(key);
  if (at == std::string::npos) return "(no can_log)";
  const size_t start = at + key.size();
  return json.substr(start, json[start] == '{' ? json.find('}', start) + 1 - start : 4);
}

/// A number field inside `object`, or -1.
long long NumberIn(const std::string& object, const std::string& key) {
  const std::string field = JsonField(object, key);
  return field.empty() ? -1 : std::stoll(field);
}

}  // namespace

TEST_CASE(
    "a lap through the CAN adapter: the JSON and the database name the kind, the candump log shows "
    "the bus") {
  const auto dir = test::ScratchDir("e2e-can");
  const auto vehicle = CanVehicleFile(dir);
  const auto db = dir / "runs.db";
  Child haptel({CanBin("haptel"), "run", "--vehicle", vehicle.string(), "--track",
                "config/tracks/test-short.yaml", "--json", "--quiet", "--domain",
                std::to_string(test::UniqueDomain(61)), "--database", db.string(),
                "--vehicle-timeout", "5", "--reality", "none"});
  const int code = haptel.Wait(120.0);
  INFO("stdout:\n" << haptel.out() << "\nstderr:\n" << haptel.err());
  REQUIRE(code == 0);
  const std::string json = haptel.LastLine();
  CHECK(JsonField(json, "completed") == "true");
  CHECK(JsonField(json, "vehicle_kind") == "can-robot-sim");
  record::Recorder recorder(db);
  const auto runs = recorder.LoadAll();
  REQUIRE(runs.size() == 1);
  CHECK(runs[0].vehicle_kind == "can-robot-sim");
  CHECK(runs[0].completed);

  // One log for the run, every line candump -L; velocity commands to both
  // wheels (node 1: 0x02D, node 2: 0x04D), both wheels' heartbeats (0x021,
  // 0x041) and the I/O node's (0x061).
  REQUIRE(std::filesystem::exists(dir / "can"));
  std::vector<std::filesystem::path> logs;
  for (const auto& e : std::filesystem::directory_iterator(dir / "can")) logs.push_back(e.path());
  REQUIRE(logs.size() == 1);
  size_t malformed = 99;
  const std::vector<vehicles::LoggedFrame> frames = vehicles::ReadCandumpLog(logs[0], &malformed);
  CHECK(malformed == 0);
  std::map<uint32_t, int> by_id;
  bool moved = false;
  for (const vehicles::LoggedFrame& f : frames) {
    by_id[f.frame.can_id] += 1;
    CHECK(f.interface == "can0");
    if (f.frame.can_id == 0x02D && f.frame.data[3] != 0) moved = true;  // a non-zero float velocity
  }
  CHECK(by_id[0x02D] > 100);
  CHECK(by_id[0x04D] > 100);
  CHECK(by_id[0x021] > 10);
  CHECK(by_id[0x041] > 10);
  CHECK(by_id[0x061] > 10);
  CHECK(by_id[0x027] >= 1);  // closed loop requested
  CHECK(moved);
  // The JSON line and the summary name the log, whole: its path, and the
  // frames in it as of the vehicle's last state.
  const std::string can_log = CanLogOf(json);
  INFO(can_log);
  CHECK(JsonField(can_log, "path") == logs[0].string());
  CHECK(NumberIn(can_log, "frames") > 0);
  CHECK(NumberIn(can_log, "frames") <= static_cast<long long>(frames.size()));
  CHECK(NumberIn(can_log, "frames_lost") == 0);
  CHECK(can_log.find("\"error\"") == std::string::npos);
  CHECK(haptel.out().find("vehicle's CAN bus log " + logs[0].string()) != std::string::npos);
}

TEST_CASE(
    "the CAN log on a full disk: both programs say so once, the summary and the JSON name it, exit "
    "5") {
  const auto dir = test::ScratchDir("e2e-can-full");
  const auto vehicle_file = CanVehicleFile(dir);
  const std::string name = "canfull";
  // A full disk without root (the log names the vehicle may take link to /dev/full).
  const auto can_dir = dir / "can";
  test::CanLogsOnFullDisk(can_dir, name);
  Child haptel({CanBin("haptel"), "run", "--vehicle", vehicle_file.string(), "--vehicle-name", name,
                "--track", "config/tracks/test-short.yaml", "--time-limit", "8", "--json",
                "--quiet", "--domain", std::to_string(test::UniqueDomain(62)), "--database",
                (dir / "runs.db").string(), "--vehicle-timeout", "5"});
  const int code = haptel.Wait(120.0);
  INFO("stdout:\n" << haptel.out() << "\nstderr:\n" << haptel.err());
  CHECK(code == 5);  // wins over the time limit's 1
  const std::string json = haptel.LastLine();
  CHECK(JsonField(json, "outcome") == "time limit");
  CHECK(std::stod(JsonField(json, "distance_m")) > 0.1);  // the robot drove on
  CHECK(JsonField(json, "recorded") == "true");
  const std::string can_log = CanLogOf(json);
  INFO(can_log);
  const std::filesystem::path log = JsonField(can_log, "path");
  CHECK(log.parent_path() == can_dir);
  CHECK(std::filesystem::is_symlink(log));
  CHECK(JsonField(can_log, "error") ==
        "cannot write " + log.string() + ": No space left on device (after 0 frames)");
  CHECK(NumberIn(can_log, "frames") == 0);
  CHECK(NumberIn(can_log, "frames_lost") > 100);
  // Said once by each program (the spawned vehicle's stderr is the run's),
  // and in the summary instead of the log's figures.
  auto count = [](const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(count(haptel.err(),
              "haptel-vehicle: error: the CAN bus log is not recorded whole: cannot write " +
                  log.string()) == 1);
  CHECK(count(haptel.err(), "haptel: error: vehicle '" + name +
                                "': its CAN bus log is not recorded whole: cannot write " +
                                log.string()) == 1);
  CHECK(haptel.out().find("vehicle's CAN bus log NOT recorded whole: cannot write " +
                          log.string()) != std::string::npos);
}
