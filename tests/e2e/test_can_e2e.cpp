// End to end through the CAN code path: `haptel run` drives the simulated CAN
// robot (the real adapter, a socket pair, emulated ODrives and I/O node) and
// the run's candump log shows the velocity commands and both heartbeats; the
// real robot's adapter on a kernel without CAN support is a one-line set-up
// error.
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <algorithm>
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
}  // namespace

TEST_CASE("a lap through the CAN adapter: the JSON and the database name the kind, the candump log shows the bus") {
  const auto dir = test::ScratchDir("e2e-can");
  // The shipped file, with its log in the test's folder.
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
  const auto db = dir / "runs.db";
  Child haptel({CanBin("haptel"), "run", "--vehicle", vehicle.string(), "--track", "config/tracks/test-short.yaml",
                "--json", "--quiet", "--domain", std::to_string(test::UniqueDomain(61)), "--database", db.string(),
                "--vehicle-timeout", "5"});
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
}

TEST_CASE("the real CAN robot on a kernel without CAN support: exit 2, one line naming errno 97") {
  const int probe = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe >= 0) {
    close(probe);
    WARN("this kernel has CAN support: the errno 97 refusal cannot be seen here");
    return;
  }
  Child vehicle({CanBin("haptel-vehicle"), "--config", "config/vehicles/can-robot.yaml", "--can", "can0"});
  CHECK(vehicle.Wait(30.0) == 2);
  INFO(vehicle.err());
  CHECK(vehicle.err().find("can0") != std::string::npos);
  CHECK(vehicle.err().find("no CAN support") != std::string::npos);
  CHECK(vehicle.err().find("errno 97") != std::string::npos);
  CHECK(std::count(vehicle.err().begin(), vehicle.err().end(), '\n') == 1);
}
