// The blimp gesture cockpit (thesis 8.2.2): right hand the stabilisers, left
// hand the engines, the tail rotor at zero power, fields to neutral, the
// camera following the head.
#include <catch2/catch.hpp>
#include <cmath>

#include "hal_fixture.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"
#include "haptel/interfaces/blimp_gesture.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::test::Metres;
using haptel::test::PutHand;
using haptics::Side;
using haptics::Vec3d;

namespace {
BlimpGestureConfig Config() {
  BlimpGestureConfig c;
  c.right_neutral = {0.1, -0.05, 0.0};
  c.left_neutral = {0.1, 0.05, 0.02};
  c.dead_zone = 0.01;
  c.full_elevator = 0.08;
  c.full_rudder = 0.08;
  c.full_power = 0.10;
  c.full_helix = 0.06;
  c.full_tail = 0.08;
  return c;
}
const Vec3d kRight{0.1, -0.05, 0.0};
const Vec3d kLeft{0.1, 0.05, 0.02};
Vec3d Plus(const Vec3d& a, double x, double y, double z) { return {a[0] + x, a[1] + y, a[2] + z}; }
}  // namespace

TEST_CASE(
    "blimp gesture: both hands at neutral give the neutral command (no power, straight ahead)") {
  BlimpGestureInterface g(Config());
  const BlimpCommand c =
      g.Map(Plus(kLeft, 0.009, -0.009, 0.009), Plus(kRight, -0.009, 0.009, 0.0), {});
  CHECK(c.elevator == 0.0);
  CHECK(c.rudder == 0.0);
  CHECK(c.power == 0.0);
  CHECK(c.helix == 0.0);
  CHECK(c.tail_rotor == 0.0);
}

TEST_CASE("blimp gesture: the right hand is a stick for the stabilisers") {
  BlimpGestureInterface g(Config());
  // Forward pushes the nose down, by the fraction past the dead zone.
  CHECK(g.Map(kLeft, Plus(kRight, 0.05, 0, 0), {}).elevator == Approx(-0.5));
  CHECK(g.Map(kLeft, Plus(kRight, -0.05, 0, 0), {}).elevator == Approx(0.5));
  // Left turns left (rudder positive), saturating at full scale.
  CHECK(g.Map(kLeft, Plus(kRight, 0, 0.03, 0), {}).rudder == Approx(0.25));
  CHECK(g.Map(kLeft, Plus(kRight, 0, -0.5, 0), {}).rudder == Approx(-1.0));
  // The right hand does nothing to the engines.
  const BlimpCommand c = g.Map(kLeft, Plus(kRight, 0.2, 0.2, 0.2), {});
  CHECK(c.power == 0.0);
  CHECK(c.helix == 0.0);
  CHECK(c.tail_rotor == 0.0);
}

TEST_CASE(
    "blimp gesture: the left hand is the power forward and the helix plane up and down; back gives "
    "no power") {
  BlimpGestureInterface g(Config());
  CHECK(g.Map(Plus(kLeft, 0.06, 0, 0), kRight, {}).power == Approx(0.5));
  CHECK(g.Map(Plus(kLeft, 0.5, 0, 0), kRight, {}).power == Approx(1.0));
  CHECK(g.Map(Plus(kLeft, -0.06, 0, 0), kRight, {}).power == 0.0);
  CHECK(g.Map(Plus(kLeft, 0, 0, 0.04), kRight, {}).helix == Approx(0.5));
  CHECK(g.Map(Plus(kLeft, 0, 0, -0.07), kRight, {}).helix == Approx(-1.0));
  // Neither hand moves the stabilisers from the left.
  const BlimpCommand c = g.Map(Plus(kLeft, 0.06, 0.0, 0.04), kRight, {});
  CHECK(c.elevator == 0.0);
  CHECK(c.rudder == 0.0);
}

TEST_CASE(
    "blimp gesture: with zero power the left hand's sideways motion drives the tail rotor (the "
    "quick turnabout), with power it does not") {
  BlimpGestureInterface g(Config());
  // Zero power (inside the dead zone, or pulled back): sideways is the tail rotor.
  CHECK(g.Map(Plus(kLeft, 0.0, 0.05, 0), kRight, {}).tail_rotor == Approx(0.5));
  CHECK(g.Map(Plus(kLeft, -0.03, -0.09, 0), kRight, {}).tail_rotor == Approx(-1.0));
  // With power, the same sideways offset means nothing.
  const BlimpCommand powered = g.Map(Plus(kLeft, 0.03, 0.05, 0), kRight, {});
  CHECK(powered.power > 0.0);
  CHECK(powered.tail_rotor == 0.0);
  CHECK(powered.rudder == 0.0);
}

TEST_CASE("blimp gesture: HandTargetsFor inverts the mapping for both hands") {
  BlimpGestureInterface g(Config());
  BlimpCommand a;
  a.elevator = 0.3;
  a.rudder = -0.6;
  a.power = 0.8;
  a.helix = -0.4;
  BlimpCommand turnabout;
  turnabout.tail_rotor = -0.7;
  turnabout.helix = 0.2;
  for (const BlimpCommand& want : {a, turnabout, BlimpCommand{}}) {
    const HandTargets t = g.HandTargetsFor(want);
    REQUIRE(t[haptics::Index(Side::kLeft)].has_value());
    REQUIRE(t[haptics::Index(Side::kRight)].has_value());
    const BlimpCommand got = g.Map(t[haptics::Index(Side::kLeft)]->position,
                                   t[haptics::Index(Side::kRight)]->position, {});
    CHECK(got.elevator == Approx(want.elevator).margin(1e-9));
    CHECK(got.rudder == Approx(want.rudder).margin(1e-9));
    CHECK(got.power == Approx(want.power).margin(1e-9));
    CHECK(got.helix == Approx(want.helix).margin(1e-9));
    CHECK(got.tail_rotor == Approx(want.tail_rotor).margin(1e-9));
  }
}

TEST_CASE(
    "blimp gesture: fields pull both hands to neutral, harder the further they are (the effort "
    "tells the speed)") {
  BlimpGestureInterface g(Config());
  haptics::Hal hal(Metres());
  PutHand(hal, Plus(kLeft, 0.05, 0, 0), Side::kLeft);
  PutHand(hal, Plus(kRight, 0, 0.04, 0), Side::kRight);
  const BlimpCommand c = g.Update({}, hal);
  CHECK(c.power > 0.0);
  CHECK(c.rudder > 0.0);
  const haptics::ForceField left = hal.Setpoint(Side::kLeft).field;
  const haptics::ForceField right = hal.Setpoint(Side::kRight).field;
  REQUIRE(left.enabled);
  REQUIRE(right.enabled);
  const double near = haptics::EvaluateForceField(left, Plus(kLeft, 0.02, 0, 0), {0, 0, 0})[0];
  const double far = haptics::EvaluateForceField(left, Plus(kLeft, 0.08, 0, 0), {0, 0, 0})[0];
  CHECK(near < 0.0);        // pulls back towards no power
  CHECK(far < 4.0 * near);  // four times the offset, more than four times the force
  CHECK(haptics::EvaluateForceField(right, Plus(kRight, 0, 0.04, 0), {0, 0, 0})[1] < 0.0);
}

TEST_CASE("blimp gesture: without both hands' samples the command is neutral and the forces zero") {
  BlimpGestureInterface g(Config());
  haptics::Hal hal(Metres());
  PutHand(hal, Plus(kRight, 0.05, 0.05, 0), Side::kRight);  // the left arm has said nothing
  hal.SetField(Side::kRight, g.field(Side::kRight));
  const BlimpCommand c = g.Update({0.2, -0.1}, hal);
  CHECK(c.elevator == 0.0);
  CHECK(c.rudder == 0.0);
  CHECK(c.power == 0.0);
  CHECK_FALSE(hal.Setpoint(Side::kRight).field.enabled);
  CHECK_FALSE(hal.Setpoint(Side::kLeft).field.enabled);
  CHECK(c.camera_pan == Approx(0.2));  // the camera still follows the head
}

TEST_CASE("blimp gesture: the camera follows the head, within the camera head's range") {
  BlimpGestureInterface g(Config());
  BlimpCommand c = g.Map(kLeft, kRight, {0.5, -0.3});
  CHECK(c.camera_pan == Approx(0.5));
  CHECK(c.camera_tilt == Approx(-0.3));
  c = g.Map(kLeft, kRight, {3.0, 2.0});
  CHECK(c.camera_pan == Approx(kBlimpCameraPanMax));
  CHECK(c.camera_tilt == Approx(kBlimpCameraTiltMax));
  c = g.Map(kLeft, kRight, {std::nan(""), -2.0});
  CHECK(c.camera_pan == 0.0);
  CHECK(c.camera_tilt == Approx(-kBlimpCameraTiltMax));
}

TEST_CASE("blimp gesture: the shipped file loads; a bad value names file and key") {
  const BlimpGestureConfig c = LoadBlimpGesture("config/interfaces/blimp-gesture.yaml");
  CHECK(c.name == "blimp-gesture");
  BlimpGestureConfig bad = Config();
  bad.full_power = 0.0;
  CHECK_THROWS_WITH(BlimpGestureInterface(bad), Catch::Contains("full_power"));
}
