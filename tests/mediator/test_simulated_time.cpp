// `haptel run --simulated-time`: every part on one simulated clock in this
// process. The same seed gives the same lap to the tick; the lap is timed
// by the same lap timer and stored in the same row as a real-time one; the
// link's delay is the configured one; what cannot be stepped here is refused.
#include <fastdds/rtps/common/SerializedPayload.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <set>
#include <string>
#include <vector>

#include "haptel/app/in_process_robot.hpp"
#include "haptel/app/run_command.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/mediator/engagement.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/session/sessionPubSubTypes.h"
#include "test_env.hpp"

using namespace haptel;

namespace {

/// `haptel run` with these words after the shared ones, into `database`.
mediator::SessionSetup Setup(const std::filesystem::path& database, std::vector<std::string> more) {
  std::vector<std::string> words = {"run",
                                    "--track",
                                    "config/tracks/test-short.yaml",
                                    "--operator",
                                    "auto",
                                    "--view",
                                    "none",
                                    "--quiet",
                                    "--database",
                                    database.string()};
  words.insert(words.end(), more.begin(), more.end());
  std::vector<const char*> argv;
  for (const std::string& w : words) argv.push_back(w.c_str());
  return mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
}

mediator::RecordedRun Run(const mediator::SessionSetup& setup) {
  app::RegisterInProcessRobot();
  record::Recorder recorder(setup.run.database);
  const std::atomic<bool> interrupted{false};
  return mediator::RunAndRecord(setup, recorder, interrupted);
}

/// Two runs of one setup are the same lap: every pose, to the tick.
void CheckSameLap(const mediator::RecordedRun& a, const mediator::RecordedRun& b) {
  const record::RunRecord& x = a.result.record;
  const record::RunRecord& y = b.result.record;
  CHECK(x.outcome == y.outcome);
  CHECK(x.lap_time_s == y.lap_time_s);  // exactly: the same ticks
  CHECK(x.approach_s == y.approach_s);
  CHECK(x.distance_m == y.distance_m);
  CHECK(x.obstacles_touched == y.obstacles_touched);
  CHECK(a.result.simulated_s == b.result.simulated_s);
  CHECK(a.result.servo_ticks == b.result.servo_ticks);
  CHECK(a.result.physics_ticks == b.result.physics_ticks);
  CHECK(a.result.vehicle_ticks == b.result.vehicle_ticks);
  REQUIRE(x.path.size() == y.path.size());
  for (size_t i = 0; i < x.path.size(); ++i) {
    INFO("path point " << i);
    CHECK(x.path[i].t_s == y.path[i].t_s);
    CHECK(x.path[i].x == y.path[i].x);
    CHECK(x.path[i].y == y.path[i].y);
  }
  REQUIRE(x.splits.size() == y.splits.size());
  for (size_t i = 0; i < x.splits.size(); ++i) CHECK(x.splits[i].split_s == y.splits[i].split_s);
}

}  // namespace

TEST_CASE("simulated time: the same seed drives the same gesture lap to the tick",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("simtime-gesture");
  const mediator::SessionSetup setup =
      Setup(dir / "runs.db", {"--interface", "gesture", "--simulated-time"});
  REQUIRE(setup.simulated_time);
  const mediator::RecordedRun first = Run(setup);
  const mediator::RecordedRun second = Run(setup);
  INFO(first.result.message);
  REQUIRE(first.result.outcome == mediator::Outcome::kCompleted);
  CheckSameLap(first, second);
  // The robot ran the default reality, lab, with its file's seed: one seed,
  // one lap. The twin (--reality none) drives another path.
  CHECK(first.result.reality == "lab");
  CHECK(first.result.reality_seed == 1);
  const mediator::RecordedRun twin = Run(
      Setup(dir / "twin.db", {"--interface", "gesture", "--simulated-time", "--reality", "none"}));
  CHECK(twin.result.reality == "none");
  REQUIRE(twin.result.outcome == mediator::Outcome::kCompleted);
  double apart_m = 0.0;
  const auto& lab_path = first.result.record.path;
  const auto& twin_path = twin.result.record.path;
  for (size_t i = 0; i < std::min(lab_path.size(), twin_path.size()); ++i) {
    apart_m = std::max(apart_m,
                       std::hypot(lab_path[i].x - twin_path[i].x, lab_path[i].y - twin_path[i].y));
  }
  INFO("lab lap " << first.result.record.lap_time_s << " s, twin's "
                  << twin.result.record.lap_time_s << " s; paths up to " << apart_m << " m apart");
  CHECK(apart_m > 0.02);
  // Every part kept its rate on the simulated clock: 1 kHz servo, the
  // vehicle's 200 Hz, for the session's whole simulated span.
  const double span_s = first.result.simulated_s;
  CHECK(first.result.servo_ticks == static_cast<uint64_t>(std::llround(span_s * 1000.0)));
  CHECK(first.result.vehicle_ticks == static_cast<uint64_t>(std::llround(span_s * 200.0)));
  CHECK_FALSE(first.result.record.servo_rate_short);
  CHECK(first.result.record.speedup > 0.0);
  // The automatic operator's hand shakes as a held hand does: engaged all
  // lap, but for the start (half a second of its motion must be seen first).
  CHECK(first.result.record.disengaged_s < mediator::HandMotionRule::kWindow_s);
  // The clock is the real one again after the run.
  CHECK_FALSE(SimulatedClockOn());
}

TEST_CASE("simulated time: a cockpit's physics steps in lock-step, the same every run",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("simtime-cockpit");
  // Long enough to grasp the wheel and the lever and drive off (the lap limit
  // ends it on the lap's clock, or before the line). Recorded whole, as a
  // real-time run is.
  const auto session = dir / "lap.mcap";
  const mediator::SessionSetup setup =
      Setup(dir / "runs.db", {"--interface", "cockpit-assisted", "--simulated-time", "--lap-limit",
                              "3", "--session", session.string()});
  const mediator::RecordedRun first = Run(setup);
  const mediator::RecordedRun second = Run(setup);
  INFO(first.result.message);
  CHECK(first.result.physics_ticks > 0);
  CHECK(first.result.grasp_s > 0.0);  // the hands held the controls: the physics moved them
  CHECK(first.result.record.distance_m > 0.1);
  CheckSameLap(first, second);
  CHECK(first.result.physics_ticks ==
        static_cast<uint64_t>(std::llround(first.result.simulated_s / setup.physics.step_s)));

  // No DDS carried the robot's commands and states, yet the session file
  // holds them as it would have; and each hand's grasp of its control.
  const record::SessionFileReport& file = second.result.session_file;
  INFO(file.error);
  REQUIRE(file.saved);
  CHECK(file.Messages("haptel/robot1/command") == second.result.commands_sent);
  CHECK(file.Messages("haptel/robot1/command") > 10);
  CHECK(file.Messages("haptel/robot1/state") > 10);
  CHECK(file.Messages("haptel/robot1/pose") == file.Messages("haptel/robot1/state"));
  const mcap::Reader reader = mcap::Reader::Open(session);
  std::set<std::string> grasps;  // "kind side control"
  reader.ForEachMessage(
      0, UINT64_MAX, {std::string(record::session::kInterfaceEventsTopic)},
      [&](const mcap::MessageView& m) {
        haptel::session::EventPubSubType type;
        haptel::session::Event e;
        eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(m.size));
        std::memcpy(payload.data, m.data, m.size);
        payload.length = static_cast<uint32_t>(m.size);
        REQUIRE(type.deserialize(&payload, &e));
        grasps.insert(std::string(e.kind().c_str()) + " " + std::to_string(e.side()) + " " +
                      e.text().c_str());
      });
  INFO("interface events:" << [&] {
    std::string all;
    for (const std::string& g : grasps) all += " [" + g + "]";
    return all;
  }());
  CHECK(grasps.count("grasp 0 wheel") == 1);
  CHECK(grasps.count("grasp 1 lever") == 1);
}

TEST_CASE("simulated time: the lap is timed and stored as a real-time one, with its speed-up",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("simtime-row");
  const mediator::SessionSetup setup =
      Setup(dir / "runs.db", {"--interface", "gesture", "--simulated-time"});
  const mediator::RecordedRun run = Run(setup);
  REQUIRE(run.run_id != 0);
  const record::RunRecord& r = run.result.record;
  REQUIRE(r.completed);
  record::Recorder recorder(setup.run.database);
  const std::vector<record::RunRecord> rows = recorder.LoadAll();
  REQUIRE(rows.size() == 1);
  const record::RunRecord& row = rows[0];
  // The lap timer's lap, gates and splits, as the session scored them.
  CHECK(row.lap_time_s == r.lap_time_s);
  CHECK(row.gates_passed == row.gates_total);
  CHECK(row.gates_total == static_cast<int>(setup.track.gates.size()));
  CHECK(row.splits.size() == r.splits.size());
  CHECK(row.approach_s == r.approach_s);
  CHECK(row.speedup == r.speedup);
  CHECK(row.speedup > 0.0);
  CHECK(row.servo_rate_hz == Approx(1000.0).epsilon(1e-3));
  CHECK(row.vehicle_pid == 0);  // nothing spawned
  CHECK(!row.path.empty());
  CHECK(!row.counters.empty());
  // A real-time run's row has no speed-up (NULL).
  record::RunRecord real = r;
  real.speedup = -1.0;
  const int64_t id = recorder.Save(real);
  CHECK(recorder.LoadAll().at(static_cast<size_t>(id - 1)).speedup == -1.0);
}

TEST_CASE("simulated time: commands and states take the link's configured delay each way",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("simtime-delay");
  const mediator::SessionSetup setup =
      Setup(dir / "runs.db", {"--interface", "gesture", "--simulated-time", "--link-fault",
                              "delay=100ms", "--lap-limit", "2"});
  const mediator::RecordedRun run = Run(setup);
  // Round trip less the wait at the vehicle: twice the delay (10 us bins).
  CHECK(run.result.record.command_rtt_ms_p50 == Approx(200.0).margin(0.02));
  CHECK(run.result.record.command_rtt_ms_p99 == Approx(200.0).margin(0.02));
}

TEST_CASE("simulated time: what cannot step in this process is refused, naming what is needed",
          "[simulated-time]") {
  const auto dir = test::ScratchDir("simtime-refused");
  const auto db = dir / "runs.db";
  // A person drives in real time (at the simulated arms nobody does: below).
  CHECK_THAT(test::WhatOf<UsageError>([&] {
               Setup(db, {"--simulated-time", "--operator", "person", "--device",
                          "config/devices/udp.yaml"});
             }),
             Catch::Contains("--operator auto"));
  CHECK_THAT(test::WhatOf<UsageError>([&] {
               Setup(db, {"--simulated-time", "--vehicle", "config/vehicles/can-robot-sim.yaml"});
             }),
             Catch::Contains("sim-robot"));
  CHECK_THAT(test::WhatOf<UsageError>([&] {
               Setup(db, {"--simulated-time", "--vehicle", "config/vehicles/sim-blimp.yaml"});
             }),
             Catch::Contains("sim-robot"));
  CHECK_THAT(test::WhatOf<UsageError>([&] {
               Setup(db, {"--simulated-time", "--link-fault", "delay=50ms,loss=5%"});
             }),
             Catch::Contains("delay alone"));
  CHECK_THAT(test::WhatOf<UsageError>([&] {
               Setup(db, {"--simulated-time", "--attach"});
             }),
             Catch::Contains("--attach"));
}

TEST_CASE("a gesture run with nobody at the simulated arms moves the vehicle 0 m in 60 s",
          "[simulated-time][engagement]") {
  const auto dir = test::ScratchDir("simtime-nobody");
  // `haptel run --operator person --device config/devices/sim.yaml --interface gesture`:
  // nobody holds the arms (issue 36: it drove off at 0.15 m/s).
  mediator::SessionSetup setup =
      Setup(dir / "runs.db", {"--operator", "person", "--device", "config/devices/sim.yaml",
                              "--interface", "gesture", "--simulated-time", "--time-limit", "60"});
  // What the view shows (as a study's console watches it live).
  std::vector<std::string> shown;
  setup.on_live = [&](const view::Overlay& o) { shown.emplace_back(o.message); };
  const mediator::RecordedRun run = Run(setup);
  const record::RunRecord& r = run.result.record;
  CHECK(run.result.outcome == mediator::Outcome::kTimeLimit);
  CHECK(r.distance_m == 0.0);
  CHECK(r.obstacles_touched == 0);
  CHECK(r.device == "sim");
  // Not engaged all along once the vehicle was up (at once, in this process).
  CHECK(r.disengaged_s == Approx(60.0).margin(1.0));
  CHECK(std::isnan(r.pseudo_haptic_gain_mean));  // the sim device bends nothing
  CHECK(r.ff_effects_played == 0);
  // The person is told, all along.
  REQUIRE(shown.size() > 100);
  CHECK(shown.back() == "Not engaged - nobody holds the device: take hold of it to drive");
  // The JSON line and the database row say the same.
  const std::string json = app::RunJson(setup, run);
  CHECK_THAT(json, Catch::Contains("\"distance_m\":0,"));
  CHECK_THAT(json, Catch::Contains("\"device\":\"sim\""));
  CHECK_THAT(json, Catch::Contains("\"pseudo_haptic_gain_mean\":null,\"ff_effects_played\":0"));
  CHECK_THAT(json, Catch::Contains("\"disengaged_s\":" + JsonNumber(r.disengaged_s)));
  const std::vector<record::RunRecord> rows = record::Recorder(setup.run.database).LoadAll();
  REQUIRE(rows.size() == 1);
  CHECK(rows[0].distance_m == 0.0);
  CHECK(rows[0].disengaged_s == r.disengaged_s);
  CHECK(rows[0].device == "sim");
}
