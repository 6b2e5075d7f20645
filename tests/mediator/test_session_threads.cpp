// A real-time run with its vehicles in this process: the session loop, the
// servo and physics threads, the link's DDS callbacks, the fleet's handover
// and the vehicle nodes' control loops and cameras, all in one program, so
// that ThreadSanitizer (scripts/test --tsan) watches them together. The
// end-to-end tests drive the same runs with each vehicle in a process of its
// own, where TSan could watch neither side's threads against the other's.
#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptel/app/run_command.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/vehicles/vehicle_kinds.hpp"
#include "test_env.hpp"
#include "virtual_joystick.hpp"

namespace fs = std::filesystem;
using namespace haptel;

namespace {

/// The shipped simulated robot as `name` on test-short, started in this
/// process on `domain`, as haptel-vehicle would start it.
std::unique_ptr<vehicles::Node> StartRobot(const std::string& name, int domain) {
  const std::string file = "config/vehicles/sim-robot.yaml";
  VehicleConfig config = LoadVehicle(file);
  config.name = name;
  config.link.domain_id = domain;
  config.world = "config/tracks/test-short.yaml";
  std::unique_ptr<vehicles::Node> node = vehicles::OpenVehicle(config, file).make_node();
  node->Start();
  return node;
}

/// `haptel run` with these words, attached to vehicles already on `domain`,
/// the automatic operator, no view, into `database`. A vehicle under
/// ThreadSanitizer on a loaded machine is slow to answer: 10 s before lost.
std::vector<std::string> AttachedRun(int domain, const fs::path& database,
                                     std::vector<std::string> more) {
  std::vector<std::string> words = {
      "run",        "--attach",   "--domain",        std::to_string(domain),
      "--operator", "auto",       "--view",          "none",
      "--quiet",    "--database", database.string(), "--vehicle-timeout",
      "10"};
  words.insert(words.end(), more.begin(), more.end());
  return words;
}

std::vector<const char*> Argv(const std::vector<std::string>& words) {
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  return argv;
}

/// A person's attached run on the short track with `device` and `interface`,
/// no view, for `time_limit_s` (a word of the command line).
mediator::SessionSetup PersonAtDevice(int domain, const fs::path& dir, const std::string& device,
                                      const std::string& interface,
                                      const std::string& time_limit_s) {
  const std::vector<std::string> words = {"run",
                                          "--attach",
                                          "--domain",
                                          std::to_string(domain),
                                          "--operator",
                                          "person",
                                          "--device",
                                          device,
                                          "--interface",
                                          interface,
                                          "--view",
                                          "none",
                                          "--quiet",
                                          "--database",
                                          (dir / "runs.db").string(),
                                          "--vehicle-timeout",
                                          "10",
                                          "--track",
                                          "config/tracks/test-short.yaml",
                                          "--time-limit",
                                          time_limit_s};
  const std::vector<const char*> argv = Argv(words);
  return mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
}

}  // namespace

TEST_CASE("a real-time run attached to a robot in this process drives it and is recorded",
          "[threads]") {
  const int domain = test::UniqueDomain();
  const fs::path dir = test::ScratchDir("session-threads-run");
  const std::unique_ptr<vehicles::Node> robot = StartRobot("robot1", domain);
  const std::vector<std::string> words = AttachedRun(
      domain, dir / "runs.db", {"--track", "config/tracks/test-short.yaml", "--time-limit", "6"});
  const std::vector<const char*> argv = Argv(words);
  const mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  mediator::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  const mediator::RecordedRun run = mediator::RunAndRecord(setup, recorder, interrupted);
  robot->Stop();

  const record::RunRecord& record = run.result.record;
  INFO("outcome " << record.outcome << ": " << run.result.message);
  CHECK((record.outcome == "time limit" || record.outcome == "completed"));
  CHECK(record.distance_m > 0.0);  // the robot obeyed the session's commands
  CHECK(run.run_id != 0);
}

TEST_CASE("a fleet of two robots in this process: both driven in turn, each recorded",
          "[threads]") {
  const int domain = test::UniqueDomain(1);  // not the run's above
  const fs::path dir = test::ScratchDir("session-threads-fleet");
  // Turned every 2 s: a few handovers in the run. robot-b is driven through
  // the cockpit, so each turn to it and away from it also starts and stops
  // its physics thread while the servo loop runs.
  const std::string robot = fs::absolute("config/vehicles/sim-robot.yaml").string();
  const std::string track = fs::absolute("config/tracks/test-short.yaml").string();
  const fs::path fleet =
      test::WriteFile(dir / "fleet.yaml",
                      "name: two-robots\nslice_s: 2\nvehicles:\n"
                      "  - {name: robot-a, vehicle: " +
                          robot + ", world: " + track +
                          "}\n"
                          "  - {name: robot-b, vehicle: " +
                          robot + ", world: " + track + ", interface: cockpit}\n");
  const std::unique_ptr<vehicles::Node> a = StartRobot("robot-a", domain);
  const std::unique_ptr<vehicles::Node> b = StartRobot("robot-b", domain);
  const fs::path database = dir / "runs.db";
  const std::vector<std::string> words =
      AttachedRun(domain, database, {"--fleet", fleet.string(), "--time-limit", "20"});
  const std::vector<const char*> argv = Argv(words);
  const std::atomic<bool> interrupted{false};
  app::RunFleetCommand(static_cast<int>(argv.size()), argv.data(), interrupted);
  a->Stop();
  b->Stop();

  // One row per robot; each moved, so the operator turned to each.
  const std::vector<record::RunRecord> rows = mediator::Recorder(database).LoadAll();
  REQUIRE(rows.size() == 2);
  for (const record::RunRecord& row : rows) {
    INFO(row.vehicle << ": " << row.outcome);
    CHECK(row.distance_m > 0.0);
    if (row.vehicle == "robot-b") CHECK(row.physics_rate_hz > 0.0);  // its cockpit's physics ran
    CHECK(row.outcome != "refused");
    CHECK(row.outcome != "vehicle lost");
  }
}

TEST_CASE("a joystick unplugged mid-run: the run ends aborted, saying so, the robot stopped",
          "[threads]") {
  test::VirtualJoystick stick(/*rumble=*/true);
  const int domain = test::UniqueDomain(2);  // not the runs' above
  const fs::path dir = test::ScratchDir("session-threads-unplugged");
  const std::unique_ptr<vehicles::Node> robot = StartRobot("robot1", domain);
  // What the robot reports, read as a second operator would.
  LinkConfig link;
  link.domain_id = domain;
  link::Participant participant(link, "test-watcher");
  std::mutex mutex;
  std::optional<msg::VehicleState> first, last;
  link::StateReader states(participant, link::TopicName("robot1", "state"), link::Profile::kState,
                           [&](const msg::VehicleState& s) {
                             std::lock_guard lock(mutex);
                             if (!first) first = s;
                             last = s;
                           });
  const auto speed = [&] {
    std::lock_guard lock(mutex);
    return last ? static_cast<double>(last->speed()) : 0.0;
  };
  const auto moved_m = [&] {
    std::lock_guard lock(mutex);
    return last ? std::hypot(last->x() - first->x(), last->y() - first->y()) : 0.0;
  };
  const mediator::SessionSetup setup =
      PersonAtDevice(domain, dir, "config/devices/sdl-ff.yaml", "gesture", "60");
  // The person holds the trigger and pushes the stick forward, from
  // neutral again now and then (a run engages only from rest); once the
  // robot has driven 10 cm, the stick is unplugged. (Not at its first
  // motion: a session thread slowed by TSan and the load, without real
  // time there, may not yet have taken the state that shows it.)
  std::thread person([&] {
    stick.SetButton(0, true);
    test::WaitFor(
        [&] {
          stick.SetAxis(1, 0);
          std::this_thread::sleep_for(std::chrono::milliseconds(300));
          stick.SetAxis(1, -20000);
          return test::WaitFor([&] { return moved_m() > 0.10; }, 3.0);
        },
        30.0);
    stick.Detach();
  });
  mediator::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  const mediator::RecordedRun run = mediator::RunAndRecord(setup, recorder, interrupted);
  person.join();
  // Held safe: the robot comes to rest (the run's stop, or its watchdog).
  const bool stopped = test::WaitFor([&] { return std::abs(speed()) < 0.01; }, 5.0);
  robot->Stop();

  const record::RunRecord& record = run.result.record;
  INFO("outcome " << record.outcome << ": " << run.result.message);
  CHECK(record.outcome == "aborted");
  CHECK_THAT(run.result.message, Catch::Contains("joystick 'Haptel test stick' was unplugged"));
  CHECK(record.distance_m > 0.0);  // it drove before: what was measured is kept
  CHECK(run.run_id != 0);
  CHECK(stopped);
}

TEST_CASE("a wheel and pedals drive the cockpit: the hands grip while the deadman is held",
          "[threads]") {
  test::VirtualJoystick wheel(/*rumble=*/true);
  wheel.SetAxis(2, 32767);  // both pedals released: they rest high
  wheel.SetAxis(3, 32767);
  const int domain = test::UniqueDomain(3);
  const fs::path dir = test::ScratchDir("session-threads-wheel");
  const std::unique_ptr<vehicles::Node> robot = StartRobot("robot1", domain);
  const mediator::SessionSetup setup =
      PersonAtDevice(domain, dir, "config/devices/sdl-ff-wheel.yaml", "cockpit", "8");
  std::thread person([&] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    wheel.SetButton(4, true);  // the deadman: the hands close on the rim and the lever
    std::this_thread::sleep_for(std::chrono::seconds(1));
    wheel.SetAxis(2, -32768);  // the accelerator down: the lever forward
  });
  mediator::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  const mediator::RecordedRun run = mediator::RunAndRecord(setup, recorder, interrupted);
  person.join();
  robot->Stop();
  const record::RunRecord& record = run.result.record;
  INFO("outcome " << record.outcome << ": " << run.result.message);
  CHECK(record.outcome == "time limit");
  CHECK(record.distance_m > 0.2);
}
