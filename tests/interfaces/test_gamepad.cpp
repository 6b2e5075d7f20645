#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/gamepad.hpp"

using namespace haptel;
using namespace haptel::interfaces;

namespace {
GamepadConfig Config() {
  GamepadConfig c;
  c.dead_zone = 0.12;
  c.trigger_dead_zone = 0.05;
  c.turn_share = 0.5;
  c.deadman = GamepadDeadman::kLeftShoulder;
  return c;
}
/// A connected pad with the deadman held and everything else at rest.
InputState Pad() {
  InputState s;
  s.pad_connected = true;
  s.pad_buttons[static_cast<int>(PadButton::kLeftShoulder)] = true;
  return s;
}
double& AxisOf(InputState& s, PadAxis a) { return s.pad_axes[static_cast<int>(a)]; }
}  // namespace

TEST_CASE("gamepad: inside the radial dead zone nothing moves", "[gamepad]") {
  InputBox box;
  GamepadInterface g(Config(), box);
  InputState s = Pad();
  AxisOf(s, PadAxis::kLeftX) = 0.08;
  AxisOf(s, PadAxis::kLeftY) = -0.08;  // radius 0.113 < 0.12
  const MotionIntent i = g.Intent(s);
  CHECK(i.forward == 0.0);
  CHECK(i.turn == 0.0);
  AxisOf(s, PadAxis::kLeftY) = -0.1;  // radius 0.128: out, both components move
  const MotionIntent o = g.Intent(s);
  CHECK(o.forward > 0.0);
  CHECK(o.turn < 0.0);
}

TEST_CASE("gamepad: past the dead zone the output grows continuously from 0 to 1", "[gamepad]") {
  InputBox box;
  GamepadInterface g(Config(), box);
  InputState s = Pad();
  double previous = 0.0;
  for (int i = 0; i <= 1000; ++i) {
    AxisOf(s, PadAxis::kLeftY) = -i / 1000.0;
    const double f = g.Intent(s).forward;
    CHECK(f >= previous);
    CHECK(f - previous < 0.002);  // no jump anywhere, in particular at the edge
    previous = f;
  }
  CHECK(previous == Approx(1.0));
  AxisOf(s, PadAxis::kLeftY) = -(0.12 + 0.44);  // halfway between the edge and full
  CHECK(g.Intent(s).forward == Approx(0.5));
  AxisOf(s, PadAxis::kLeftY) = 1.0;  // pulled back: reverse
  CHECK(g.Intent(s).forward == Approx(-1.0));
}

TEST_CASE("gamepad: nothing drives unless the deadman button is held", "[gamepad]") {
  InputBox box;
  InputState s = Pad();
  AxisOf(s, PadAxis::kLeftY) = -1.0;
  SECTION("default: left shoulder") {
    GamepadInterface g(Config(), box);
    CHECK(g.Map(s).left == Approx(1.0));
    s.pad_buttons[static_cast<int>(PadButton::kLeftShoulder)] = false;
    const TreadCommand m = g.Map(s);
    CHECK(m.left == 0.0);
    CHECK(m.right == 0.0);
  }
  SECTION("another button") {
    GamepadConfig c = Config();
    c.deadman = GamepadDeadman::kA;
    GamepadInterface g(c, box);
    CHECK(g.Map(s).left == 0.0);  // the shoulder is not the deadman now
    s.pad_buttons[static_cast<int>(PadButton::kA)] = true;
    CHECK(g.Map(s).left == Approx(1.0));
  }
  SECTION("none: always drives") {
    GamepadConfig c = Config();
    c.deadman = GamepadDeadman::kNone;
    GamepadInterface g(c, box);
    s.pad_buttons = {};
    CHECK(g.Map(s).left == Approx(1.0));
  }
}

TEST_CASE("gamepad: right trigger adds speed, left trigger takes it away, clamped", "[gamepad]") {
  InputBox box;
  GamepadInterface g(Config(), box);
  InputState s = Pad();
  AxisOf(s, PadAxis::kTriggerRight) = 1.0;
  CHECK(g.Intent(s).forward == Approx(1.0));
  AxisOf(s, PadAxis::kTriggerRight) = 0.03;  // resting slack of a worn trigger
  CHECK(g.Intent(s).forward == 0.0);
  AxisOf(s, PadAxis::kTriggerRight) = 0.0;
  AxisOf(s, PadAxis::kTriggerLeft) = 1.0;
  CHECK(g.Intent(s).forward == Approx(-1.0));
  AxisOf(s, PadAxis::kTriggerLeft) = 0.0;
  AxisOf(s, PadAxis::kTriggerRight) = 1.0;
  AxisOf(s, PadAxis::kLeftY) = -1.0;  // stick and trigger together: clamped at 1
  CHECK(g.Intent(s).forward == Approx(1.0));
  AxisOf(s, PadAxis::kTriggerLeft) = 1.0;  // both triggers cancel; the stick remains
  CHECK(g.Intent(s).forward == Approx(1.0));
  AxisOf(s, PadAxis::kLeftY) = 0.0;
  CHECK(g.Intent(s).forward == 0.0);
}

TEST_CASE("gamepad: stick left turns left (right motor faster), from either stick", "[gamepad]") {
  InputBox box;
  InputState s = Pad();
  SECTION("left stick") {
    GamepadInterface g(Config(), box);
    AxisOf(s, PadAxis::kLeftX) = -1.0;
    CHECK(g.Intent(s).turn == Approx(0.5));  // × turn_share
    const TreadCommand m = g.Map(s);
    CHECK(m.right > m.left);
    AxisOf(s, PadAxis::kLeftX) = 1.0;
    const TreadCommand r = g.Map(s);
    CHECK(r.left > r.right);
    AxisOf(s, PadAxis::kRightX) = -1.0;  // the other stick does nothing here
    CHECK(g.Map(s).left > g.Map(s).right);
  }
  SECTION("right stick") {
    GamepadConfig c = Config();
    c.turn_axis = GamepadTurnAxis::kRightX;
    GamepadInterface g(c, box);
    AxisOf(s, PadAxis::kLeftX) = 1.0;  // ignored for turning
    AxisOf(s, PadAxis::kRightX) = -1.0;
    CHECK(g.Intent(s).turn == Approx(0.5));
    AxisOf(s, PadAxis::kLeftX) = 0.0;
    AxisOf(s, PadAxis::kLeftY) = -1.0;
    AxisOf(s, PadAxis::kRightX) = 0.0;
    CHECK(g.Intent(s).turn == 0.0);
    CHECK(g.Intent(s).forward == Approx(1.0));  // full forward and no turn at once
  }
}

TEST_CASE("gamepad: no controller gives zero; a disconnect during the run is lost for good",
          "[gamepad]") {
  InputBox box;
  InputState s = Pad();
  s.pad_disconnects = 2;  // earlier runs' controllers went away: not ours
  AxisOf(s, PadAxis::kLeftY) = -1.0;
  box.Store(s);
  haptics::Hal hal;
  GamepadInterface g(Config(), box);
  CHECK_FALSE(g.lost());
  CHECK(g.Update(0.0, {}, hal).left == Approx(1.0));

  s.pad_connected = false;  // not (yet) there: zero, but not lost
  box.Store(s);
  CHECK(g.Update(0.02, {}, hal).left == 0.0);
  CHECK_FALSE(g.lost());

  s.pad_connected = true;
  box.Store(s);
  CHECK(g.Update(0.04, {}, hal).left == Approx(1.0));

  s.pad_connected = false;
  s.pad_disconnects = 3;
  box.Store(s);
  TreadCommand m = g.Update(0.06, {}, hal);
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
  CHECK(g.lost());
  // Plugged back in: still lost (the run is aborted), still zero.
  s.pad_connected = true;
  box.Store(s);
  m = g.Update(0.08, {}, hal);
  CHECK(m.left == 0.0);
  CHECK(g.lost());
}

TEST_CASE("gamepad: no hands, no physics, no forces", "[gamepad]") {
  InputBox box;
  haptics::Hal hal;
  GamepadInterface g(Config(), box);
  const HandTargets targets = g.HandTargetsFor({1.0, 0.0});
  CHECK_FALSE(targets[0].has_value());
  CHECK_FALSE(targets[1].has_value());
  CHECK_FALSE(g.NeedsPhysics());
  CHECK(g.name() == "gamepad");
  g.Update(0.0, {}, hal);
  CHECK_FALSE(hal.Setpoint(haptics::Side::kLeft).field.enabled);
  CHECK_FALSE(hal.Setpoint(haptics::Side::kRight).field.enabled);
}

TEST_CASE("gamepad: refuses a config GamepadConfig::ValidateOrThrow refuses", "[gamepad]") {
  InputBox box;
  GamepadConfig c = Config();
  c.dead_zone = std::nan("");
  CHECK_THROWS_WITH(GamepadInterface(c, box),
                    Catch::Contains("dead_zone: expected a number in [0, 0.9]"));
  CHECK_THROWS_AS(GamepadInterface(c, box), ConfigFieldError);
}
