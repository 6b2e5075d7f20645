// haptel replay --drive: recorded commands sent again, at their recorded
// times from when the vehicle answers, to a simulated robot spawned as a
// run spawns it; its lap timed on the run's track.
#include <atomic>
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "haptel/mediator/run_setup.hpp"
#include "haptel/replay/drive_again.hpp"
#include "test_env.hpp"

using namespace haptel;

TEST_CASE("recorded commands sent again drive a simulated robot through the gate they led it to") {
  const std::string domain = std::to_string(test::UniqueDomain(81));
  // The twin (--reality none): an open-loop drive cannot hold a course in
  // the lab reality's skid, and what is tested is the replay, not the robot.
  const std::vector<const char*> argv{"run",       "--track",  "config/tracks/test-short.yaml",
                                      "--view",    "none",     "--operator",
                                      "auto",      "--domain", domain.c_str(),
                                      "--reality", "none"};
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  setup.vehicle_program = test::BinDir() / "haptel-vehicle";
  // From the start, behind the line on the closing side's tangent (heading
  // south-east), onto the first side (east) and through its gate: on, then
  // a left turn of about 45 degrees, then on; 50 Hz, as a run sends them.
  replay::RecordedDrive recorded;
  recorded.first_state_ns = 1'000'000'000'000;
  const auto command_at = [&](double t) -> TreadCommand {
    if (t < 0.9) return {0.8, 0.8};
    if (t < 1.4) return {0.2, 0.8};
    if (t < 3.0) return {0.8, 0.8};
    return {0.0, 0.0};
  };
  for (int i = 0; i < 175; ++i) {
    const double t = i * 0.02;
    recorded.commands.push_back(
        {recorded.first_state_ns + static_cast<uint64_t>(t * 1e9), command_at(t)});
  }
  recorded.gates = 1;
  const std::atomic<bool> interrupted{false};
  const replay::DriveReport r = replay::DriveAgain(recorded, setup, interrupted);
  INFO("watchdog stops while commands were due: " << r.watchdog_stops);
  CHECK(r.commands_sent > 100);  // one per due command, a late loop skipping some
  CHECK(r.commands_sent <= recorded.commands.size());
  CHECK(r.gates_total == 2);
  CHECK(r.gates_passed == 1);
  CHECK_FALSE(r.completed);
  CHECK(r.Reproduced());
}
