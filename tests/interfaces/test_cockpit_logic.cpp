#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/cockpit_logic.hpp"

using namespace haptel;
using namespace haptel::interfaces;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
CockpitConfig Plain() {
  CockpitConfig c;
  c.turn_share = 0.5;
  c.wheel_full_turn_deg = 90;
  c.throttle_travel = 0.06;
  c.shake_s = 0.6;
  c.shake_hz = 10;
  c.shake_torque = 0.3;
  c.throttle_lock_s = 1.0;
  return c;
}
}  // namespace

TEST_CASE("throttle drives forward, wheel turns, both saturate") {
  CockpitLogic logic(Plain());
  CockpitControls c;
  c.throttle = 0.03;  // half travel
  TreadCommand m = logic.Map(c, 0.0);
  CHECK(m.left == Approx(0.5));
  CHECK(m.right == Approx(0.5));
  c.wheel_angle = 45 * kDeg;  // half of full turn, left
  m = logic.Map(c, 0.0);
  CHECK(m.right - m.left == Approx(2 * 0.5 * 0.5));
  c.wheel_angle = 135 * kDeg;  // past full turn: saturates
  c.throttle = 1.0;            // past the end stop: saturates
  m = logic.Map(c, 0.0);
  CHECK(std::abs(m.left) <= 1.0);
  CHECK(std::abs(m.right) <= 1.0);
  CHECK(m.right > m.left);
}

TEST_CASE("ControlsFor inverts Map") {
  CockpitLogic logic(Plain());
  for (const MotionIntent intent :
       {MotionIntent{0.6, 0.2}, MotionIntent{-0.3, -0.1}, MotionIntent{0.0, 0.4}}) {
    const TreadCommand m = logic.Map(logic.ControlsFor(intent), 0.0);
    CHECK(m.left == Approx(intent.forward - intent.turn).margin(1e-9));
    CHECK(m.right == Approx(intent.forward + intent.turn).margin(1e-9));
  }
}

TEST_CASE(
    "a bumper contact shakes the wheel for shake_s and locks the throttle for throttle_lock_s") {
  CockpitLogic logic(Plain());
  CockpitControls c;
  c.throttle = 0.06;
  c.wheel_held = c.throttle_held = true;
  ControlActuation a = logic.Update(0.0, {}, c);
  CHECK(a.wheel_torque == 0.0);
  CHECK_FALSE(a.throttle_locked);
  logic.Update(1.0, {true, false, 0.0}, c);  // contact
  double peak = 0.0;
  for (double t = 1.0; t < 1.6; t += 0.005)
    peak = std::max(peak, std::abs(logic.Update(t, {}, c).wheel_torque));
  CHECK(peak == Approx(0.3).epsilon(0.05));
  CHECK(logic.Update(1.65, {}, c).wheel_torque == 0.0);  // shake over
  a = logic.Update(1.9, {}, c);
  CHECK(a.throttle_locked);
  CHECK(a.throttle_target == 0.0);
  CHECK(logic.Map(c, 1.9).left == Approx(0.0));  // full throttle held, but locked: no forward
  a = logic.Update(2.05, {}, c);
  CHECK_FALSE(a.throttle_locked);
  CHECK(logic.Map(c, 2.05).left == Approx(1.0));
}

TEST_CASE("a contact that persists does not restart the shake; a new contact does") {
  CockpitLogic logic(Plain());
  CockpitControls c;
  logic.Update(0.0, {false, true, 0.0}, c);
  logic.Update(0.5, {false, true, 0.0}, c);  // still touching
  CHECK_FALSE(logic.shaking(0.7));
  logic.Update(0.8, {}, c);
  logic.Update(0.9, {true, true, 0.0}, c);  // a new contact
  CHECK(logic.shaking(1.2));
}

TEST_CASE("only the assisted cockpit springs released controls back to zero") {
  CockpitControls released;
  CockpitLogic plain(Plain());
  ControlActuation a = plain.Update(0.0, {}, released);
  CHECK(a.wheel_spring == 0.0);
  CHECK(a.throttle_spring == 0.0);
  CockpitConfig assisted_config = Plain();
  assisted_config.return_to_zero = true;
  CockpitLogic assisted(assisted_config);
  a = assisted.Update(0.0, {}, released);
  CHECK(a.wheel_spring == assisted_config.wheel_return_stiffness);
  CHECK(a.throttle_spring == assisted_config.throttle_return_stiffness);
  CHECK(a.throttle_target == 0.0);
  CockpitControls held;
  held.wheel_held = held.throttle_held = true;
  a = assisted.Update(0.1, {}, held);
  CHECK(a.wheel_spring == 0.0);  // a held control is the driver's
  CHECK(a.throttle_spring == 0.0);
}

TEST_CASE("the HUD shows speed and turn indicators only on HUD cockpits") {
  CockpitControls c;
  c.wheel_angle = 40 * kDeg;
  CockpitLogic plain(Plain());
  CHECK_FALSE(plain.Hud({false, false, 0.2}, c, 0.0).turn_left);
  CockpitConfig hud_config = Plain();
  hud_config.hud = true;
  CockpitLogic hud(hud_config);
  HudState h = hud.Hud({false, false, 0.2}, c, 0.0);
  CHECK(h.speed == 0.2);
  CHECK(h.turn_left);
  CHECK_FALSE(h.turn_right);
  c.wheel_angle = -5 * kDeg;  // within the dead band
  h = hud.Hud({}, c, 0.0);
  CHECK_FALSE(h.turn_left);
  CHECK_FALSE(h.turn_right);
}

TEST_CASE("the shipped cockpit files load with their variants") {
  const CockpitConfig plain = LoadCockpit("config/interfaces/cockpit.yaml");
  const CockpitConfig hud = LoadCockpit("config/interfaces/cockpit-hud.yaml");
  const CockpitConfig assisted = LoadCockpit("config/interfaces/cockpit-assisted.yaml");
  CHECK_FALSE(plain.hud);
  CHECK_FALSE(plain.return_to_zero);
  CHECK(hud.hud);
  CHECK_FALSE(hud.return_to_zero);
  CHECK(assisted.hud);
  CHECK(assisted.return_to_zero);
  CHECK(plain.wheel_max_angle_deg == 135);
  CHECK_THROWS_AS(LoadCockpit("config/interfaces/gesture.yaml"),
                  ConfigError);  // wrong name, unknown keys
}

TEST_CASE("cockpit logic: refuses a config CockpitConfig::ValidateOrThrow refuses") {
  CockpitConfig c = Plain();
  c.wheel_full_turn_deg = 150;  // past the end stops (135)
  CHECK_THROWS_WITH(CockpitLogic(c),
                    Catch::Contains("wheel.full_turn_deg: expected full_turn_deg <= "
                                    "max_angle_deg"));
  CHECK_THROWS_AS(CockpitLogic(c), ConfigFieldError);
}
