#include <catch2/catch.hpp>
#include <cmath>

#include "hal_fixture.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"
#include "haptel/interfaces/gesture.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::test::Metres;
using haptel::test::PutHand;
using haptics::Side;

namespace {
GestureConfig Config() {
  GestureConfig c;
  c.neutral = {0.1, 0.0, 0.0};
  c.dead_zone = 0.01;
  c.full_forward = 0.08;
  c.full_turn = 0.08;
  c.turn_share = 0.5;
  c.wall_release_s = 0.3;
  return c;
}
}  // namespace

TEST_CASE("inside the dead zone the robot does not move") {
  GestureInterface g(Config());
  const TreadCommand m = g.Map({0.1 + 0.009, -0.009, 0.0});
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
}

TEST_CASE("hand forward drives forward, proportionally past the dead zone") {
  GestureInterface g(Config());
  const TreadCommand half = g.Map({0.1 + 0.01 + 0.04, 0, 0});
  CHECK(half.left == Approx(0.5));
  CHECK(half.right == Approx(0.5));
  const TreadCommand full = g.Map({0.1 + 0.5, 0, 0});  // far past full scale: saturates
  CHECK(full.left == Approx(1.0));
  const TreadCommand back = g.Map({0.1 - 0.05, 0, 0});
  CHECK(back.left == Approx(-0.5));
}

TEST_CASE("hand left turns left: right motor faster than left") {
  GestureInterface g(Config());
  const TreadCommand m = g.Map({0.1 + 0.05, 0.05, 0});
  CHECK(m.right > m.left);
  const TreadCommand spin = g.Map({0.1, -0.09, 0});  // pure right turn: spin in place
  CHECK(spin.left == Approx(-spin.right));
  CHECK(spin.left > 0.0);
}

TEST_CASE("commands stay within [-1, 1] at every corner of the workspace") {
  GestureInterface g(Config());
  for (double x : {-0.3, 0.0, 0.3})
    for (double y : {-0.3, 0.0, 0.3}) {
      const TreadCommand m = g.Map({0.1 + x, y, 0});
      CHECK(std::abs(m.left) <= 1.0);
      CHECK(std::abs(m.right) <= 1.0);
    }
}

TEST_CASE("HandTargetsFor inverts the mapping and uses only the right hand") {
  GestureInterface g(Config());
  for (const MotionIntent intent :
       {MotionIntent{0.6, 0.2}, MotionIntent{-0.3, -0.1}, MotionIntent{0.0, 0.0}}) {
    const HandTargets targets = g.HandTargetsFor(intent);
    REQUIRE(targets[haptics::Index(Side::kRight)].has_value());
    CHECK_FALSE(targets[haptics::Index(Side::kLeft)].has_value());
    const TreadCommand m = g.Map(targets[haptics::Index(Side::kRight)]->position);
    CHECK(m.left == Approx(intent.forward - intent.turn).margin(1e-9));
    CHECK(m.right == Approx(intent.forward + intent.turn).margin(1e-9));
  }
}

TEST_CASE("Update puts a centring field for the right hand in the HAL") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  PutHand(hal, {0.15, 0, 0});
  const TreadCommand m = g.Update(0.0, {}, hal);
  CHECK(m.left > 0.0);
  const haptics::ForceField right = hal.Setpoint(Side::kRight).field;
  CHECK(right.enabled);
  const haptics::Vec3d f = haptics::EvaluateForceField(right, {0.15, 0, 0}, {0, 0, 0});
  CHECK(f[0] < 0.0);  // pulls back toward neutral
  CHECK_FALSE(hal.Setpoint(Side::kLeft).field.enabled);
}

TEST_CASE("CommandNow maps the hand's latest sample and sets no field") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  const std::optional<TreadCommand> none = g.CommandNow(0.0, hal);
  REQUIRE(none);
  CHECK(none->left == 0.0);  // no sample yet: stopped, as Update
  PutHand(hal, {0.15, 0.02, 0});
  const std::optional<TreadCommand> now = g.CommandNow(0.0, hal);
  REQUIRE(now);
  const TreadCommand mapped = g.Map({0.15, 0.02, 0});
  CHECK(now->left == mapped.left);
  CHECK(now->right == mapped.right);
  CHECK_FALSE(hal.Setpoint(Side::kRight).field.enabled);  // the tick's Update sets fields, not this
}

TEST_CASE("without a valid hand sample Update commands stop and zero forces") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  hal.SetField(Side::kRight, g.field());
  const TreadCommand m = g.Update(0.0, {}, hal);
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
  CHECK_FALSE(hal.Setpoint(Side::kRight).field.enabled);
}

TEST_CASE("a bumper contact raises a haptic wall that resists further forward motion") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  const haptics::Vec3d at_contact{0.16, 0.0, 0.0};
  PutHand(hal, at_contact);
  g.Update(0.0, {}, hal);
  CHECK_FALSE(g.wall_active());
  g.Update(0.1, {true, true, 0.0}, hal);
  REQUIRE(g.wall_active());
  const haptics::ForceField field = hal.Setpoint(Side::kRight).field;
  // Compare the force 1 cm further forward with and without the wall.
  haptics::ForceField no_wall = field;
  no_wall.wall_active = false;
  const haptics::Vec3d further{0.17, 0.0, 0.0};
  const double with = haptics::EvaluateForceField(field, further, {0, 0, 0})[0];
  const double without = haptics::EvaluateForceField(no_wall, further, {0, 0, 0})[0];
  CHECK(with < without - 5.0);  // at least 5 N more resistance 1 cm into the wall
  // Pulling back is not resisted by the wall.
  const haptics::Vec3d back{0.14, 0.0, 0.0};
  CHECK(haptics::EvaluateForceField(field, back, {0, 0, 0})[0] ==
        Approx(haptics::EvaluateForceField(no_wall, back, {0, 0, 0})[0]));
}

TEST_CASE("a left-only contact tilts the wall toward the left") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  PutHand(hal, {0.16, 0.02, 0.0});
  g.Update(0.0, {true, false, 0.0}, hal);
  REQUIRE(g.wall_active());
  CHECK(g.field().wall_normal[0] > 0.0);
  CHECK(g.field().wall_normal[1] > 0.0);
  GestureInterface g2(Config());
  g2.Update(0.0, {false, true, 0.0}, hal);
  CHECK(g2.field().wall_normal[1] < 0.0);
}

TEST_CASE("the wall releases once the contact has been clear for wall_release_s") {
  GestureInterface g(Config());
  haptics::Hal hal(Metres());
  PutHand(hal, {0.16, 0, 0});
  g.Update(0.0, {true, false, 0.0}, hal);
  g.Update(1.0, {true, false, 0.0}, hal);  // still touching
  g.Update(1.1, {}, hal);                  // cleared 0.1 s ago
  CHECK(g.wall_active());
  g.Update(1.29, {}, hal);
  CHECK(g.wall_active());
  g.Update(1.31, {}, hal);
  CHECK_FALSE(g.wall_active());
  CHECK_FALSE(hal.Setpoint(Side::kRight).field.wall_active);
}

TEST_CASE("gesture: refuses a config GestureConfig::ValidateOrThrow refuses") {
  GestureConfig c;
  c.full_forward = 0.0;
  CHECK_THROWS_WITH(GestureInterface(c),
                    Catch::Contains("full_forward: expected a number in [0.005, 0.5]"));
  CHECK_THROWS_AS(GestureInterface(c), ConfigFieldError);
}
