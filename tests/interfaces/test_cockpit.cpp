// The cockpit interface around its logic: it reads the controls and actuates
// them through its port, exposes the HUD, and puts the operator's hands on
// the rim and the bar where the wanted control positions are.
#include <catch2/catch.hpp>
#include <cmath>

#include "hal_fixture.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/cockpit.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::test::Metres;
using haptel::test::PutHand;
using haptics::Side;

namespace {

/// Controls whose state the test sets, recording what the interface asks.
struct PlainPort final : ControlsPort {
  CockpitControls state;
  ControlActuation last;
  int actuations = 0;
  CockpitControls Controls() const override { return state; }
  void Actuate(const ControlActuation& a) override {
    last = a;
    ++actuations;
  }
};

CockpitConfig Shipped(const char* name) {
  return LoadCockpit(ShippedFile(std::string("config/interfaces/") + name + ".yaml"));
}

}  // namespace

TEST_CASE("cockpit: Update maps the controls read through the port and actuates them") {
  PlainPort port;
  CockpitInterface cockpit(Shipped("cockpit"), port);
  haptics::Hal hal(Metres());
  CHECK(cockpit.name() == "cockpit");
  CHECK(cockpit.NeedsPhysics());

  port.state = {.wheel_angle = 0.0, .throttle = 0.03, .wheel_held = true, .throttle_held = true};
  TreadCommand m = cockpit.Update(0.0, {}, hal);
  CHECK(m.left == Approx(0.5));
  CHECK(m.right == Approx(0.5));
  CHECK(port.actuations == 1);
  CHECK_FALSE(port.last.throttle_locked);
  CHECK(port.last.wheel_torque == 0.0);

  // Wheel turned left: the right track runs faster.
  port.state.wheel_angle = 0.5;
  m = cockpit.Update(0.1, {}, hal);
  CHECK(m.right > m.left);
  CHECK(cockpit.controls().wheel_angle == 0.5);

  // A bumper contact: the port is told to shake the wheel and lock the lever
  // at zero, and the motors stop driving forward while it is locked.
  const VehicleFeedback bump(/*bumper_left=*/true, /*bumper_right=*/false, /*speed=*/0.1);
  m = cockpit.Update(0.2, bump, hal);
  CHECK(port.last.throttle_locked);
  CHECK(port.last.throttle_target == 0.0);
  CHECK(m.left + m.right == Approx(0.0).margin(1e-12));                       // turning only
  cockpit.Update(0.2 + 0.25 / cockpit.logic().config().shake_hz, bump, hal);  // a quarter period on
  CHECK(std::abs(port.last.wheel_torque) > 0.5 * cockpit.logic().config().shake_torque);
  // Past the lock and the shake, the lever is free again.
  const double after =
      0.2 + std::max(cockpit.logic().config().throttle_lock_s, cockpit.logic().config().shake_s) +
      0.01;
  m = cockpit.Update(after, {}, hal);
  CHECK_FALSE(port.last.throttle_locked);
  CHECK(port.last.wheel_torque == 0.0);
  CHECK(m.left + m.right > 0.5);
}

TEST_CASE("cockpit: CommandNow is Update's command for the controls now, and actuates nothing") {
  PlainPort port;
  CockpitInterface cockpit(Shipped("cockpit-assisted"), port);
  haptics::Hal hal(Metres());
  port.state = {.wheel_angle = 0.2, .throttle = 0.01, .wheel_held = true, .throttle_held = true};
  const TreadCommand updated = cockpit.Update(0.0, {}, hal);
  REQUIRE(port.actuations == 1);
  // The lever moved on since the tick: the command between ticks is the new one's.
  port.state.throttle = 0.02;
  const std::optional<TreadCommand> now = cockpit.CommandNow(0.005, hal);
  REQUIRE(now);
  CHECK(now->left + now->right > updated.left + updated.right);
  CHECK(port.actuations == 1);
  CHECK(cockpit.controls().throttle == 0.01);  // what the tick read, untouched
  const TreadCommand next = cockpit.Update(0.01, {}, hal);
  CHECK(now->left == Approx(next.left));
  CHECK(now->right == Approx(next.right));
  // A contact locks the lever: between ticks too, nothing forward.
  cockpit.Update(0.02, VehicleFeedback(true, true, 0.1), hal);
  port.state.wheel_angle = 0.0;
  const std::optional<TreadCommand> locked = cockpit.CommandNow(0.025, hal);
  REQUIRE(locked);
  CHECK(locked->left == 0.0);
  CHECK(locked->right == 0.0);
}

TEST_CASE("cockpit: only the HUD cockpits show speed and indicators") {
  PlainPort port;
  port.state.wheel_angle = 0.6;
  haptics::Hal hal(Metres());
  const VehicleFeedback moving(false, false, /*speed=*/0.25);
  CockpitInterface plain(Shipped("cockpit"), port);
  plain.Update(0.0, moving, hal);
  CHECK(plain.hud().speed == 0.0);
  CHECK_FALSE(plain.hud().turn_left);

  CockpitInterface hud(Shipped("cockpit-hud"), port);
  hud.Update(0.0, moving, hal);
  CHECK(hud.hud().speed == 0.25);
  CHECK(hud.hud().turn_left);
  CHECK_FALSE(hud.hud().turn_right);
}

TEST_CASE("cockpit-assisted: the port is told to spring a released control back, not a held one") {
  PlainPort port;
  haptics::Hal hal(Metres());
  const CockpitConfig config = Shipped("cockpit-assisted");
  CockpitInterface assisted(config, port);
  port.state = {.wheel_angle = 0.4, .throttle = 0.02, .wheel_held = true, .throttle_held = true};
  assisted.Update(0.0, {}, hal);
  CHECK(port.last.wheel_spring == 0.0);
  CHECK(port.last.throttle_spring == 0.0);
  port.state.wheel_held = port.state.throttle_held = false;
  assisted.Update(0.1, {}, hal);
  CHECK(port.last.wheel_spring == config.wheel_return_stiffness);
  CHECK(port.last.throttle_spring == config.throttle_return_stiffness);
  CHECK(port.last.throttle_target == 0.0);

  CockpitInterface plain(Shipped("cockpit"), port);
  plain.Update(0.2, {}, hal);
  CHECK(port.last.wheel_spring == 0.0);
  CHECK(port.last.throttle_spring == 0.0);
}

TEST_CASE("cockpit: the hand goals sit on the rim and the bar where the intent puts them") {
  PlainPort port;
  const CockpitConfig c = Shipped("cockpit");
  const GripGeometry grip;
  CockpitInterface cockpit(c, port, grip);
  const MotionIntent intent{.forward = 0.5, .turn = 0.35};
  const CockpitControls wanted = cockpit.logic().ControlsFor(intent);
  REQUIRE(wanted.wheel_angle > 0.1);
  const HandTargets targets = cockpit.HandTargetsFor(intent);
  REQUIRE(targets[haptics::Index(Side::kLeft)]);
  REQUIRE(targets[haptics::Index(Side::kRight)]);
  const HandGoal& wheel = *targets[haptics::Index(Side::kLeft)];
  const HandGoal& lever = *targets[haptics::Index(Side::kRight)];

  // Wheel hand: behind the rim by `reach`, on the circle of radius r + height
  // about the hub, at the wheel's angle (+ = left: towards +y), and turned
  // with it about −x.
  CHECK(wheel.position[0] == Approx(c.wheel_hub[0] - grip.reach));
  const double dy = wheel.position[1] - c.wheel_hub[1];
  const double dz = wheel.position[2] - c.wheel_hub[2];
  CHECK(std::hypot(dy, dz) == Approx(c.wheel_radius + grip.height));
  CHECK(std::atan2(dy, dz) == Approx(wanted.wheel_angle));
  CHECK(wheel.orientation[0] == Approx(std::cos(0.5 * wanted.wheel_angle)));
  CHECK(wheel.orientation[1] == Approx(-std::sin(0.5 * wanted.wheel_angle)));
  // It comes in along its own back (the turned +z), from `approach` away.
  CHECK(std::hypot(wheel.approach[1], wheel.approach[2]) == Approx(grip.approach));
  CHECK(std::atan2(wheel.approach[1], wheel.approach[2]) == Approx(wanted.wheel_angle));

  // Lever hand: over the bar, fingers across it (to −y), shifted forward
  // with the throttle.
  CHECK(lever.position[0] == Approx(c.throttle_centre[0] + wanted.throttle));
  CHECK(lever.position[1] == Approx(c.throttle_centre[1] + grip.reach));
  CHECK(lever.orientation[0] == Approx(std::sqrt(0.5)));
  CHECK(lever.orientation[3] == Approx(-std::sqrt(0.5)));
  CHECK(lever.position[2] == Approx(c.throttle_centre[2] + grip.height));
  CHECK(lever.approach[2] == Approx(grip.approach));

  // Both closed: the four fingers flexed, the thumb open.
  for (const HandGoal* g : {&wheel, &lever}) {
    CHECK(g->glove[0] == 0.0);
    CHECK(g->glove[4] == grip.flexion[0]);
    CHECK(g->glove[4 + 3 * 3 + 1] == grip.flexion[1]);
  }
  // Neutral: wheel straight (hand at the top), lever at the centre.
  const HandTargets neutral = cockpit.HandTargetsFor({});
  CHECK(neutral[0]->position[1] == Approx(c.wheel_hub[1]));
  CHECK(neutral[1]->position[0] == Approx(c.throttle_centre[0]));
}

TEST_CASE(
    "cockpit: a control that slipped in the hand is made up for, as a person watching it would") {
  PlainPort port;
  const CockpitConfig c = Shipped("cockpit");
  const GripGeometry grip;
  CockpitInterface cockpit(c, port, grip);
  haptics::Hal hal(Metres());
  const MotionIntent intent{.forward = 0.5, .turn = 0.0};
  const double nominal_x =
      cockpit.HandTargetsFor(intent)[haptics::Index(Side::kRight)]->position[0];
  // The right hand is 2 cm further forward than its grip would put it on the
  // lever; the wheel 0.1 rad behind the left hand (hand on the rim's top).
  port.state = {.wheel_angle = -0.1, .throttle = 0.01, .wheel_held = true, .throttle_held = true};
  for (int i = 1; i <= 300; ++i) {
    PutHand(hal, {c.throttle_centre[0] + 0.03, c.throttle_centre[1] + grip.reach, 0.0},
            Side::kRight, i * 10'000'000LL);
    PutHand(hal, {c.wheel_hub[0] - grip.reach, c.wheel_hub[1], c.wheel_hub[2] + c.wheel_radius},
            Side::kLeft, i * 10'000'000LL);
    cockpit.Update(i * 0.01, {}, hal);
  }
  CHECK(cockpit.lever_slip() == Approx(0.02).margin(1e-4));
  CHECK(cockpit.wheel_slip() == Approx(0.1).margin(1e-3));
  const HandTargets t = cockpit.HandTargetsFor(intent);
  CHECK(t[haptics::Index(Side::kRight)]->position[0] == Approx(nominal_x + 0.02).margin(1e-4));
  CHECK(std::atan2(t[haptics::Index(Side::kLeft)]->position[1] - c.wheel_hub[1],
                   t[haptics::Index(Side::kLeft)]->position[2] - c.wheel_hub[2]) ==
        Approx(0.1).margin(1e-3));
  // Let go: nothing to make up for.
  port.state.throttle_held = port.state.wheel_held = false;
  cockpit.Update(3.01, {}, hal);
  CHECK(cockpit.lever_slip() == 0.0);
  CHECK(cockpit.wheel_slip() == 0.0);
}

TEST_CASE("cockpit: refuses a config CockpitConfig::ValidateOrThrow refuses") {
  PlainPort port;
  CockpitConfig c = Shipped("cockpit");
  c.throttle_travel = 0.0;
  CHECK_THROWS_WITH(CockpitInterface(c, port), Catch::Contains("throttle.travel"));
  CHECK(port.actuations == 0);
}
