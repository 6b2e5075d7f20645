// Haptic shared control on hand-made cases: scans of a wall or a post at known
// places, the vehicle of the shipped files (0.3 m/s, treads 0.16 m apart,
// body radius 0.11 m), a clearance of 0.03 m: the body may come within 0.14 m.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "hal_fixture.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/interfaces/shared_control.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::test::Metres;
using haptel::test::PutHand;
using haptics::Side;
using haptics::Vec3d;

namespace {
constexpr double kRangeMax = 1.5;
const VehicleGeometry kVehicle{.max_speed = 0.3, .track_width = 0.16, .body_radius = 0.11};

/// 31 beams over ±90°, nothing within range.
RangeScan Empty() {
  RangeScan s;
  s.count = 31;
  s.angle_min = -std::numbers::pi / 2;
  s.angle_increment = std::numbers::pi / 30;
  s.range_max = kRangeMax;
  s.ranges.fill(static_cast<float>(kRangeMax));
  return s;
}
/// A wall across the path, `distance` ahead (vehicle frame: the line x = distance).
RangeScan WallAhead(double distance) {
  RangeScan s = Empty();
  for (int i = 0; i < s.count; ++i) {
    const double c = std::cos(s.Angle(i));
    if (c > 1e-6 && distance / c < kRangeMax)
      s.ranges[static_cast<size_t>(i)] = static_cast<float>(distance / c);
  }
  return s;
}
/// A wall along the path, `offset` to the right (the line y = −offset).
RangeScan WallAlongRight(double offset) {
  RangeScan s = Empty();
  for (int i = 0; i < s.count; ++i) {
    const double sn = -std::sin(s.Angle(i));
    if (sn > 1e-6 && offset / sn < kRangeMax)
      s.ranges[static_cast<size_t>(i)] = static_cast<float>(offset / sn);
  }
  return s;
}
/// One beam meets something at (range, angle of that beam).
RangeScan PointAt(int beam, double range) {
  RangeScan s = Empty();
  s.ranges[static_cast<size_t>(beam)] = static_cast<float>(range);
  return s;
}

GestureConfig SharedConfig(double horizon_s = 1.5, double max_force = 3.0) {
  GestureConfig c;
  c.name = "gesture-shared";
  c.neutral = {0.0, 0.0, 0.0};
  c.dead_zone = 0.01;
  c.full_forward = 0.08;
  c.full_turn = 0.08;
  c.turn_share = 0.7;
  c.shared_control = {.enabled = true,
                      .horizon_s = horizon_s,
                      .max_force = max_force,
                      .stiffness = 150.0,
                      .clearance = 0.03};
  return c;
}

/// The guidance of gesture-shared with the hand at `hand` and the vehicle seeing `scan`.
Guidance GuideAt(const Vec3d& hand, const RangeScan& scan,
                 const GestureConfig& config = SharedConfig()) {
  GestureInterface g(config, kVehicle);
  haptics::Hal hal(Metres());
  PutHand(hal, hand);
  VehicleFeedback feedback;
  feedback.ranges = scan;
  g.Update(0.0, feedback, hal);
  return g.guidance();
}
}  // namespace

TEST_CASE("time to collision: the commanded arc against what the beams met") {
  // Full ahead at 0.3 m/s, a wall 0.5 m ahead: the body reaches 0.14 m from
  // it after 0.36 m, at 1.2 s.
  CHECK(TimeToCollision(WallAhead(0.5), {1.0, 1.0}, kVehicle, 0.03, 2.0) ==
        Approx(1.2).margin(0.005));
  // Half speed: twice as long.
  CHECK(TimeToCollision(WallAhead(0.5), {0.5, 0.5}, kVehicle, 0.03, 3.0) ==
        Approx(2.4).margin(0.01));
  // Beyond the horizon: none.
  CHECK(std::isinf(TimeToCollision(WallAhead(0.5), {1.0, 1.0}, kVehicle, 0.03, 1.0)));
  // Backing away, standing, turning on the spot: none.
  CHECK(std::isinf(TimeToCollision(WallAhead(0.5), {-1.0, -1.0}, kVehicle, 0.03, 2.0)));
  CHECK(std::isinf(TimeToCollision(WallAhead(0.5), {0.0, 0.0}, kVehicle, 0.03, 2.0)));
  CHECK(std::isinf(TimeToCollision(WallAhead(0.2), {-0.5, 0.5}, kVehicle, 0.03, 2.0)));
  // A post beside the path (beam 23, at +48°, 0.566 m: 0.42 m to the left of it): passed, not met.
  CHECK(std::isinf(TimeToCollision(PointAt(23, 0.566), {1.0, 1.0}, kVehicle, 0.03, 3.0)));
  // The same post is met on a left arc through it (radius 0.38 m: right tread 1.53 times the left).
  CHECK(TimeToCollision(PointAt(23, 0.566), {0.6, 0.92}, kVehicle, 0.03, 3.0) < 3.0);
  // Driving along a wall already nearer than the clearance is not a collision.
  CHECK(std::isinf(TimeToCollision(WallAlongRight(0.12), {1.0, 1.0}, kVehicle, 0.03, 3.0)));
  // No range sensors: nothing to see.
  CHECK(std::isinf(TimeToCollision(RangeScan{}, {1.0, 1.0}, kVehicle, 0.03, 3.0)));
}

TEST_CASE("an obstacle ahead within the horizon pushes the hand back") {
  // Hand at full forward: TTC (0.45 − 0.14) / 0.3 ≈ 1.03 s, inside 1.5 s.
  const Guidance g = GuideAt({0.09, 0.0, 0.0}, WallAhead(0.45));
  REQUIRE(g.active);
  CHECK(g.time_to_collision_s == Approx(1.033).margin(0.01));
  CHECK(g.danger == Approx(1.0 - 1.033 / 1.5).margin(0.01));
  CHECK(g.force[0] < -0.1);                                   // back, towards slower
  CHECK(std::abs(g.force[1]) < 0.05 * std::abs(g.force[0]));  // straight back: the wall is square
  CHECK(g.normal[0] > 0.99);
  // The boundary: the fastest forward command that stops in time, reached by pulling back.
  CHECK(g.point[0] < 0.09);
  CHECK(g.point[0] > 0.01);
}

TEST_CASE("an obstacle beyond the horizon or beside the path does not push") {
  // 1.4 m ahead at full speed: 4.2 s away, beyond 1.5 s.
  const Guidance far = GuideAt({0.09, 0.0, 0.0}, WallAhead(1.4));
  CHECK_FALSE(far.active);
  CHECK(far.force == Vec3d{});
  // A post 0.4 m to the side of a straight path.
  const Guidance beside = GuideAt({0.09, 0.0, 0.0}, PointAt(23, 0.566));
  CHECK_FALSE(beside.active);
  // The hand at neutral stops the vehicle: nothing to push away from, even against a wall.
  CHECK_FALSE(GuideAt({0.0, 0.0, 0.0}, WallAhead(0.2)).active);
  // Plain gesture has no shared control at all.
  GestureConfig plain = SharedConfig();
  plain.name = "gesture";
  plain.shared_control.enabled = false;
  GestureInterface g(plain, kVehicle);
  CHECK_FALSE(g.CurrentGuidance().has_value());
}

TEST_CASE("turning towards an obstacle on the left pushes the hand to the right") {
  // Forward and a little left, a post ahead-left (beam 18, at +18°, 0.4 m away).
  const Guidance g = GuideAt({0.07, 0.02, 0.0}, PointAt(18, 0.4));
  REQUIRE(g.active);
  CHECK(g.force[1] < 0.0);
  // Mirrored: a post ahead-right while turning right pushes the hand left.
  const Guidance mirrored = GuideAt({0.07, -0.02, 0.0}, PointAt(12, 0.4));
  REQUIRE(mirrored.active);
  CHECK(mirrored.force[1] > 0.0);
}

TEST_CASE("curving into a wall beside the path steers the hand away rather than slowing it") {
  // Three quarters forward and a right turn (treads about 0.93 and 0.58:
  // 0.22 m/s on an arc of radius about 0.35 m to the right), a wall along
  // the right 0.25 m off: the arc reaches 0.14 m from it within the horizon.
  // Slowing down on the same arc meets the same wall later, so it is not a
  // way out; turning less to the right is. The push is sideways, to the left,
  // and its boundary is where the path clears the wall (the earlier law,
  // judging commands by time alone, put it where the path still meets it).
  const Vec3d hand{0.07, -0.03, 0.0};
  const Guidance g = GuideAt(hand, WallAlongRight(0.25));
  REQUIRE(g.active);
  CHECK(g.force[1] > 0.0);
  CHECK(std::abs(g.force[1]) > 2.0 * std::abs(g.force[0]));
  // The boundary lies to the left of the hand, and the spring past it is the
  // file's stiffness times the hand's depth, within the bound.
  CHECK(g.point[1] > hand[1]);
  const double depth = (hand[0] - g.point[0]) * g.normal[0] + (hand[1] - g.point[1]) * g.normal[1];
  CHECK(std::hypot(g.force[0], g.force[1]) == Approx(std::min(150.0 * depth, 3.0)).margin(1e-9));
  // At the boundary the path clears the wall within the horizon, driven at
  // the hand's speed (the look-ahead is horizon x the hand's speed).
  GestureInterface gesture(SharedConfig(), kVehicle);
  const TreadCommand own = gesture.Map(hand);
  const TreadCommand boundary = gesture.Map(g.point);
  const double scale = (own.left + own.right) / (boundary.left + boundary.right);
  const TreadCommand same_speed{boundary.left * scale, boundary.right * scale};
  CHECK(std::isinf(TimeToCollision(WallAlongRight(0.25), same_speed, kVehicle, 0.03, 1.5)));
  CHECK(std::isfinite(TimeToCollision(WallAlongRight(0.25), own, kVehicle, 0.03, 1.5)));
}

TEST_CASE("the guidance is bounded: the operator can always push through") {
  const GestureConfig config = SharedConfig(1.5, 2.5);
  // A wall 0.16 m ahead: any forward command meets it at once.
  const Guidance g = GuideAt({0.09, 0.0, 0.0}, WallAhead(0.16), config);
  REQUIRE(g.active);
  CHECK(std::hypot(g.force[0], g.force[1]) == Approx(2.5));
  // As the servo loop renders it: however far the hand goes past the
  // boundary, the guidance term never pushes harder than max_force.
  GestureInterface gesture(config, kVehicle);
  haptics::Hal hal(Metres());
  PutHand(hal, {0.09, 0.0, 0.0});
  VehicleFeedback feedback;
  feedback.ranges = WallAhead(0.16);
  gesture.Update(0.0, feedback, hal);
  haptics::ForceField guidance_only = gesture.field();
  guidance_only.stiffness = guidance_only.stiffness_growth = guidance_only.damping = 0.0;
  REQUIRE(guidance_only.guidance_active);
  for (double x : {0.02, 0.05, 0.09, 0.3, 1.0}) {
    const Vec3d f = haptics::EvaluateForceField(guidance_only, {x, 0.0, 0.0}, {});
    CHECK(std::hypot(f[0], f[1], f[2]) <= 2.5 + 1e-9);
  }
  const Vec3d deep = haptics::EvaluateForceField(guidance_only, {1.0, 0.0, 0.0}, {});
  CHECK(deep[0] == Approx(-2.5));
  // And the command stays the hand's: pushing through still drives forward.
  CHECK(gesture.Map({0.09, 0.0, 0.0}).left == Approx(1.0));
}

TEST_CASE("shared control's settings are validated") {
  GestureConfig c = SharedConfig();
  c.shared_control.max_force = 40.0;
  CHECK_THROWS_WITH(GestureInterface(c, kVehicle), Catch::Contains("shared_control.max_force"));
  c = SharedConfig();
  c.shared_control.horizon_s = 0.0;
  CHECK_THROWS_WITH(GestureInterface(c, kVehicle), Catch::Contains("shared_control.horizon_s"));
}

// cockpit-shared: the same prediction and guidance in the controls' space (the
// lever's travel forward, the rim's arc to the left), handed to the physics
// world as the actuation's guidance spring.
namespace {

/// Controls whose state the test sets, recording what the interface asks.
struct ControlsAt final : ControlsPort {
  CockpitControls state;
  ControlActuation last;
  CockpitControls Controls() const override { return state; }
  void Actuate(const ControlActuation& a) override { last = a; }
};

CockpitConfig SharedCockpit(double horizon_s = 1.5, double max_force = 3.0) {
  CockpitConfig c;  // the shipped geometry: radius 0.12 m, travel 0.06 m, full turn 90°
  c.name = "cockpit-shared";
  c.shared_control = {.enabled = true,
                      .horizon_s = horizon_s,
                      .max_force = max_force,
                      .stiffness = 150.0,
                      .clearance = 0.03};
  return c;
}

struct CockpitAt {
  ControlsAt port;
  CockpitInterface cockpit;
  TreadCommand command;
  CockpitAt(double throttle, double wheel_angle, const RangeScan& scan,
            const CockpitConfig& config = SharedCockpit())
      : cockpit(config, port, GripGeometry{}, kVehicle) {
    port.state = {.wheel_angle = wheel_angle,
                  .throttle = throttle,
                  .wheel_held = true,
                  .throttle_held = true};
    haptics::Hal hal(Metres());
    VehicleFeedback feedback;
    feedback.ranges = scan;
    command = cockpit.Update(0.0, feedback, hal);
  }
};

}  // namespace

TEST_CASE(
    "cockpit-shared: an obstacle ahead pushes the lever towards slower, in physics, bounded") {
  // Full forward on the lever (0.06 m): TTC (0.45 − 0.14) / 0.3 ≈ 1.03 s, inside 1.5 s.
  const CockpitAt c(0.06, 0.0, WallAhead(0.45));
  const Guidance& g = c.cockpit.guidance();
  REQUIRE(g.active);
  CHECK(g.time_to_collision_s == Approx(1.033).margin(0.01));
  CHECK(g.force[0] < -0.1);  // back, towards slower
  CHECK(std::abs(g.force[1]) <
        0.05 * std::abs(g.force[0]));  // the wheel is left alone: the wall is square
  // What the physics world is asked to render: the plane between the lever
  // and neutral, facing forward, with the file's stiffness and bound.
  const ControlActuation& a = c.port.last;
  REQUIRE(a.guidance_active);
  CHECK(a.guidance_normal_throttle > 0.99);
  CHECK(a.guidance_throttle < 0.06);
  CHECK(a.guidance_throttle > 0.005);
  CHECK(a.guidance_stiffness == 150.0);
  CHECK(a.guidance_max_force == 3.0);
  CHECK(std::hypot(g.force[0], g.force[1]) <= 3.0 + 1e-9);
  // Never locking: the lever is not held, and the command stays the controls' own.
  CHECK_FALSE(a.throttle_locked);
  CHECK(c.command.left == Approx(1.0));
  CHECK(c.command.right == Approx(1.0));
  // The view sees it as it sees gesture-shared's.
  REQUIRE(c.cockpit.CurrentGuidance().has_value());
  CHECK(c.cockpit.CurrentGuidance()->force[0] == g.force[0]);
}

TEST_CASE("cockpit-shared: steering towards a post on the left turns the wheel back to the right") {
  // Lever at 0.75 of full, wheel 0.196 rad left (turn 0.0875): the gesture
  // case's command, with the post ahead-left (beam 18, +18°, 0.4 m).
  const CockpitAt left(0.045, 0.196, PointAt(18, 0.4));
  REQUIRE(left.cockpit.guidance().active);
  CHECK(left.cockpit.guidance().force[1] < 0.0);    // along the rim, to the right
  CHECK(left.port.last.guidance_normal_rim > 0.0);  // the danger lies further left
  // Mirrored.
  const CockpitAt right(0.045, -0.196, PointAt(12, 0.4));
  REQUIRE(right.cockpit.guidance().active);
  CHECK(right.cockpit.guidance().force[1] > 0.0);
  CHECK(right.port.last.guidance_normal_rim < 0.0);
}

TEST_CASE(
    "cockpit-shared: nothing pushes beyond the horizon or at rest; plain cockpit has no shared "
    "control") {
  const CockpitAt far(0.06, 0.0, WallAhead(1.4));
  CHECK_FALSE(far.cockpit.guidance().active);
  CHECK_FALSE(far.port.last.guidance_active);
  const CockpitAt rest(0.0, 0.0, WallAhead(0.2));  // lever at zero stops the vehicle
  CHECK_FALSE(rest.cockpit.guidance().active);
  CockpitConfig plain = SharedCockpit();
  plain.name = "cockpit";
  plain.shared_control.enabled = false;
  const CockpitAt none(0.06, 0.0, WallAhead(0.45), plain);
  CHECK_FALSE(none.cockpit.CurrentGuidance().has_value());
  CHECK_FALSE(none.port.last.guidance_active);
  // Validated as gesture-shared's.
  ControlsAt port;
  CHECK_THROWS_WITH(CockpitInterface(SharedCockpit(1.5, 40.0), port, GripGeometry{}, kVehicle),
                    Catch::Contains("shared_control.max_force"));
}

TEST_CASE(
    "a false echo that lasts one scan does not reach shared control; an obstacle that stays does") {
  PersistentEchoes echoes;
  const RangeScan wall = WallAhead(0.6);
  // The first scan has nothing to be checked against: taken as it is.
  CHECK(echoes.Filter(wall).ranges == wall.ranges);
  // A speckle in the second scan, and the same scan again (the interface steps faster than
  // states come): not a second look, so the speckle stays out.
  RangeScan wall_speckle = wall;
  wall_speckle.ranges[0] = 0.2f;
  CHECK_FALSE(echoes.Filter(wall_speckle).Hit(0));
  CHECK_FALSE(echoes.Filter(wall_speckle).Hit(0));
  CHECK(echoes.Filter(wall_speckle).Hit(15));
  // The wall 1 cm nearer in the next scan: it stands, and the path meets it as the raw scan's does.
  const RangeScan nearer = WallAhead(0.59);
  const double raw = TimeToCollision(nearer, {1.0, 1.0}, kVehicle, 0.03, 3.0);
  REQUIRE(std::isfinite(raw));
  CHECK(TimeToCollision(echoes.Filter(nearer), {1.0, 1.0}, kVehicle, 0.03, 3.0) == Approx(raw));
  // A false echo straight ahead for one scan, in a clear field: left out, while the raw
  // scan would stop the vehicle.
  const RangeScan clear = Empty();
  echoes.Filter(clear);
  RangeScan speckle = clear;
  speckle.ranges[15] = 0.3f;
  speckle.ranges[16] = static_cast<float>(kRangeMax) - 0.001f;  // a different scan
  REQUIRE(std::isfinite(TimeToCollision(speckle, {1.0, 1.0}, kVehicle, 0.03, 3.0)));
  CHECK(std::isinf(TimeToCollision(echoes.Filter(speckle), {1.0, 1.0}, kVehicle, 0.03, 3.0)));
  // A turn shifts the obstacle by a beam between scans: still the same obstacle.
  RangeScan post = clear, post_turned = clear;
  post.ranges[15] = 0.4f;
  post_turned.ranges[16] = 0.41f;
  echoes.Filter(post);
  CHECK(echoes.Filter(post_turned).Hit(16));
}
