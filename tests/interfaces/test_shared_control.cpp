// Haptic shared control on hand-made cases: scans of a wall or a post at known
// places, the vehicle of the shipped files (0.3 m/s, treads 0.16 m apart,
// body radius 0.11 m), a clearance of 0.03 m: the body may come within 0.14 m.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "hal_fixture.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"
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
    if (c > 1e-6 && distance / c < kRangeMax) s.ranges[static_cast<size_t>(i)] = static_cast<float>(distance / c);
  }
  return s;
}
/// A wall along the path, `offset` to the right (the line y = −offset).
RangeScan WallAlongRight(double offset) {
  RangeScan s = Empty();
  for (int i = 0; i < s.count; ++i) {
    const double sn = -std::sin(s.Angle(i));
    if (sn > 1e-6 && offset / sn < kRangeMax) s.ranges[static_cast<size_t>(i)] = static_cast<float>(offset / sn);
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
  c.shared_control = {.enabled = true, .horizon_s = horizon_s, .max_force = max_force, .stiffness = 150.0,
                      .clearance = 0.03};
  return c;
}

/// The guidance of gesture-shared with the hand at `hand` and the vehicle seeing `scan`.
Guidance GuideAt(const Vec3d& hand, const RangeScan& scan, const GestureConfig& config = SharedConfig()) {
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
  CHECK(TimeToCollision(WallAhead(0.5), {1.0, 1.0}, kVehicle, 0.03, 2.0) == Approx(1.2).margin(0.005));
  // Half speed: twice as long.
  CHECK(TimeToCollision(WallAhead(0.5), {0.5, 0.5}, kVehicle, 0.03, 3.0) == Approx(2.4).margin(0.01));
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
  CHECK(g.force[0] < -0.1);                                 // back, towards slower
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
