// The session's parts, each on its own: the interface set's switch (forces
// ramp, no jolt), the device part's calibration policy, replay alignment.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "../interfaces/hal_fixture.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/haptics/force_field.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/interface_set.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::mediator::InterfaceSet;

namespace {

GestureConfig Gesture(const std::string& name, double neutral_x) {
  GestureConfig c;
  c.name = name;
  c.neutral = {neutral_x, 0.0, 0.0};
  return c;
}

/// The right hand's force as the servo loop would render it now.
haptics::Vec3d RightForce(const haptics::Hal& hal, const haptics::Vec3d& hand) {
  return haptics::EvaluateForceField(hal.Setpoint(haptics::Side::kRight).field, hand, {0, 0, 0});
}

}  // namespace

TEST_CASE(
    "switching interfaces ramps the forces down and up: no jump, zero command meanwhile, "
    "recorded") {
  haptics::Hal hal(test::Metres());
  const haptics::Vec3d hand{0.03, 0.0, 0.0};
  test::PutHand(hal, hand);
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> list;
  // Two interfaces that pull the same hand opposite ways: a switch without a
  // ramp would flip the force at once.
  list.push_back(std::make_unique<interfaces::GestureInterface>(Gesture("near", 0.0)));
  list.push_back(nullptr);  // listed, not built
  list.push_back(std::make_unique<interfaces::GestureInterface>(Gesture("far", 0.06)));
  const double ramp_s = 0.3;
  InterfaceSet set(std::move(list), 0, ramp_s);
  const interfaces::VehicleFeedback feedback;

  double t = 0.0;
  const double dt = 0.01;
  set.Update(t, feedback, hal);
  const double before = RightForce(hal, hand)[0];
  REQUIRE(before < -0.5);  // pulled back towards x = 0

  CHECK_FALSE(set.Request(1, t));  // not built
  CHECK_FALSE(set.Request(0, t));  // already current
  REQUIRE(set.Request(2, t));
  CHECK_FALSE(set.Request(0, t));  // one switch at a time
  double largest_step = 0.0;
  double previous = before;
  bool all_zero_commands = true;
  for (int i = 0; i < 100 && set.switching(); ++i) {
    t += dt;
    const TreadCommand m = set.Update(t, feedback, hal);
    // Zero while the switch is under way (the tick that ends the ramp drives).
    if (set.switching()) all_zero_commands = all_zero_commands && m.left == 0.0 && m.right == 0.0;
    const double f = RightForce(hal, hand)[0];
    largest_step = std::max(largest_step, std::abs(f - previous));
    previous = f;
  }
  CHECK_FALSE(set.switching());
  CHECK(all_zero_commands);
  CHECK(set.current().name() == "far");
  const double after = RightForce(hal, hand)[0];
  CHECK(after > 0.5);  // now pulled forwards, towards x = 0.06
  CHECK(hal.force_scale() == 1.0);
  // The whole change spread over two ramps of 30 ticks each: no step is more
  // than a few ramp increments.
  const double ramp_step = std::max(std::abs(before), std::abs(after)) * dt / ramp_s;
  CHECK(largest_step <= 1.5 * ramp_step);
  REQUIRE(set.switches().size() == 1);
  CHECK(set.switches()[0].from == "near");
  CHECK(set.switches()[0].to == "far");
  CHECK(set.switches()[0].t_s == Approx(ramp_s).margin(dt));
  // Driving again once the ramp is over.
  test::PutHand(hal, {0.06 + 0.05, 0.0, 0.0});
  const TreadCommand drive = set.Update(t + dt, feedback, hal);
  CHECK(drive.left > 0.1);
}

TEST_CASE("the HAL's force scale scales every force the set-point asks for") {
  haptics::Hal hal(test::Metres());
  haptics::ForceField field;
  field.enabled = true;
  field.stiffness = 100.0;
  hal.SetField(haptics::Side::kRight, field);
  haptics::ForceSetpoint coupling;
  coupling.coupling_enabled = true;
  coupling.coupling_stiffness = 200.0;
  coupling.finger_forces = {1, 2, 3, 4, 5};
  coupling.wrist_force = {1, 0, 0};
  hal.SetSetpoint(haptics::Side::kRight, coupling, 1);
  hal.SetForceScale(0.25);
  const haptics::ForceSetpoint sp = hal.Setpoint(haptics::Side::kRight);
  CHECK(sp.field.stiffness == 25.0);
  CHECK(sp.coupling_stiffness == 50.0);
  CHECK(sp.finger_forces[4] == 1.25);
  CHECK(sp.wrist_force[0] == 0.25);
  hal.SetForceScale(7.0);  // clamped
  CHECK(hal.force_scale() == 1.0);
}

TEST_CASE("calibration policy: a real device needs its own measured calibration") {
  const auto dir = test::ScratchDir("calibration-policy");
  DeviceConfig udp;
  udp.file = dir / "udp.yaml";
  udp.name = "arms";
  udp.driver = "udp";
  SECTION("none named") {
    CHECK_THROWS_WITH(mediator::DeviceCalibrationFor(udp),
                      Catch::Contains("haptel calibrate --device") && Catch::Contains("udp.yaml"));
  }
  SECTION("named but missing") {
    udp.calibration = dir / "nowhere.yaml";
    CHECK_THROWS_WITH(mediator::DeviceCalibrationFor(udp),
                      Catch::Contains("does not exist") && Catch::Contains("haptel calibrate"));
  }
  SECTION("measured on another device") {
    DeviceCalibration other;
    other.device = "sim";
    udp.calibration = dir / "sim.yaml";
    SaveCalibration(udp.calibration, other);
    CHECK_THROWS_WITH(mediator::DeviceCalibrationFor(udp), Catch::Contains("stale"));
  }
  SECTION("its own") {
    DeviceCalibration own;
    own.device = "arms";
    own.arms[0].tracker_scale = {0.02, 0.02, 0.02};
    udp.calibration = dir / "arms.yaml";
    SaveCalibration(udp.calibration, own);
    const auto got = mediator::DeviceCalibrationFor(udp);
    REQUIRE(got);
    CHECK(got->arms[0].tracker_scale[0] == 0.02);
  }
  SECTION("the sim without a file calibrates itself") {
    DeviceConfig sim;
    CHECK_FALSE(mediator::DeviceCalibrationFor(sim).has_value());
  }
  SECTION("the mouse reports SI: without a file, the identity (metres as metres)") {
    DeviceConfig mouse = LoadDevice(ShippedFile("config/devices/mouse.yaml"));
    mouse.servo.realtime_priority = 0;
    mouse.servo.lock_memory = false;
    const auto identity = mediator::DeviceCalibrationFor(mouse);
    REQUIRE(identity.has_value());
    mediator::HapticSide side(mouse, identity, std::nullopt, OperatorConfig{}, {});
    side.Tick(1'000'000);
    side.Tick(2'000'000);
    // The key hand rests where the file says, in metres, through the HAL.
    const haptics::HandSample left = side.hal().LatestSample(haptics::Side::kLeft);
    REQUIRE(left.valid);
    for (int i = 0; i < 3; ++i) CHECK(left.position[i] == Approx(mouse.mouse.key_hand_rest[i]));
  }
  SECTION("a replay uses the calibration recorded beside its trace") {
    DeviceConfig replay;
    replay.file = dir / "replay.yaml";
    replay.driver = "replay";
    replay.replay.trace = dir / "lap.trace";
    CHECK_THROWS_WITH(mediator::DeviceCalibrationFor(replay),
                      Catch::Contains("haptel run --trace"));
    DeviceCalibration recorded;
    recorded.device = "sim";
    recorded.arms[1].tracker_offset = {0.1, 0.0, 0.0};
    SaveCalibration(mediator::TraceCalibrationFile(replay.replay.trace), recorded);
    const auto got = mediator::DeviceCalibrationFor(replay);
    REQUIRE(got);
    CHECK(got->arms[1].tracker_offset[0] == 0.1);
  }
}

TEST_CASE("a held replay reports its first readings until Begin, then plays from that moment") {
  std::vector<haptics::TraceRecord> records;
  for (int i = 0; i < 10; ++i) {
    haptics::WristRaw w;
    w.position = {static_cast<double>(i), 0, 0};
    haptics::TraceRecord r = haptics::TraceRecord::FromWrist(haptics::Side::kRight, w);
    r.t_ns = 1'000'000'000 + i * 1'000'000;  // 1 ms apart
    records.push_back(r);
  }
  haptics::DeviceDescription d;
  haptics::ReplayDevice replay(records, d, false);
  replay.HoldUntilBegin();
  haptics::WristRaw out;
  REQUIRE(replay.ReadWrist(haptics::Side::kRight, 5'000'000'000, out) ==
          haptics::DeviceStatus::kOk);
  CHECK(out.position[0] == 0.0);
  REQUIRE(replay.ReadWrist(haptics::Side::kRight, 9'000'000'000, out) ==
          haptics::DeviceStatus::kOk);
  CHECK(out.position[0] == 0.0);  // still holding, however late
  CHECK_FALSE(replay.finished(9'000'000'000));
  replay.Begin(10'000'000'000);
  REQUIRE(replay.ReadWrist(haptics::Side::kRight, 10'000'000'000 + 4'500'000, out) ==
          haptics::DeviceStatus::kOk);
  CHECK(out.position[0] == 4.0);
  CHECK(replay.finished(10'000'000'000 + 20'000'000));
}

TEST_CASE("a paused trace writer lets records go without counting them as dropped") {
  const auto dir = test::ScratchDir("trace-pause");
  const auto file = dir / "t.trace";
  {
    haptics::TraceWriter writer(file);
    writer.SetRecording(false);
    haptics::WristRaw w;
    for (int i = 0; i < 5; ++i)
      CHECK(writer.Push(haptics::TraceRecord::FromWrist(haptics::Side::kLeft, w)));
    writer.SetRecording(true);
    for (int i = 0; i < 3; ++i)
      CHECK(writer.Push(haptics::TraceRecord::FromWrist(haptics::Side::kLeft, w)));
    CHECK(writer.dropped() == 0);
  }
  CHECK(haptics::ReadTrace(file).size() == 3);
}

TEST_CASE(
    "an interface built when first asked for fills its empty place and can then be switched to") {
  haptics::Hal hal(test::Metres());
  test::PutHand(hal, {0.03, 0.0, 0.0});
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> list;
  list.push_back(std::make_unique<interfaces::GestureInterface>(Gesture("near", 0.0)));
  list.push_back(nullptr);  // waits for its parts (a physics world)
  InterfaceSet set(std::move(list), 0, 0.1);
  CHECK_FALSE(set.Request(1, 0.0));
  set.Provide(1, std::make_unique<interfaces::GestureInterface>(Gesture("far", 0.06)));
  REQUIRE(set.Request(1, 0.0));
  const interfaces::VehicleFeedback feedback;
  for (double t = 0.0; t < 0.5; t += 0.01) set.Update(t, feedback, hal);
  CHECK(set.current_index() == 1);
  CHECK(set.current().name() == "far");
  // Only an empty place takes one, and only a place the run lists.
  CHECK_THROWS_AS(
      set.Provide(1, std::make_unique<interfaces::GestureInterface>(Gesture("again", 0.0))),
      std::invalid_argument);
  CHECK_THROWS_AS(
      set.Provide(2, std::make_unique<interfaces::GestureInterface>(Gesture("beyond", 0.0))),
      std::invalid_argument);
}

TEST_CASE(
    "every robot interface of the table loads from its shipped file with the table's hands and "
    "physics") {
  const RunConfig run = LoadRun(ShippedFile("config/haptel.yaml"));
  interfaces::InputBox input;
  interfaces::InterfaceParts parts;
  parts.input = &input;
  int robot = 0;
  for (const InterfaceKindInfo& kind : InterfaceKinds()) {
    if (kind.family != VehicleFamily::kRobot) continue;
    INFO(kind.name);
    ++robot;
    const interfaces::InterfaceSpec spec = interfaces::LoadInterfaceSpec(run, kind.name);
    CHECK(spec.name == kind.name);
    CHECK(spec.hands() == kind.hands);
    CHECK(spec.needs_physics() == kind.physics);
    CHECK(spec.manual() == kind.manual());
    if (kind.physics) {
      // Its controls are bodies: without a world it cannot be built.
      CHECK_THROWS_AS(interfaces::MakeInterface(spec, parts), std::invalid_argument);
    } else {
      CHECK(interfaces::MakeInterface(spec, parts)->name() == kind.name);
    }
  }
  CHECK(robot == 8);  // gesture, gesture-shared, the four cockpits (cockpit-shared among them),
                      // keyboard, gamepad
  // A blimp's interface is refused for the robot, naming the robot's.
  CHECK_THROWS_WITH(
      interfaces::LoadInterfaceSpec(run, "blimp-gesture"),
      Catch::Contains("flies a blimp") && Catch::Contains("gesture, gesture-shared, cockpit"));
}
