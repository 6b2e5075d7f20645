#include <catch2/catch.hpp>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/keyboard.hpp"

using namespace haptel;
using namespace haptel::interfaces;

namespace {
/// What the input thread would publish: keys go down and up, counters count.
struct Keys {
  InputBox box;
  InputState s;
  void Down(bool InputState::*held, uint32_t InputState::*presses) {
    s.*held = true;
    ++(s.*presses);
    box.Store(s);
  }
  void Up(bool InputState::*held) {
    s.*held = false;
    box.Store(s);
  }
  /// Down and up between two ticks: shorter than a session tick.
  void Tap(bool InputState::*held, uint32_t InputState::*presses) {
    Down(held, presses);
    Up(held);
  }
};

KeyboardConfig Config() {
  KeyboardConfig c;
  c.repeat_s = 0.12;
  c.release_to_zero = true;
  c.turn_share = 0.5;
  return c;
}

constexpr double kTick = 0.02;  // a 50 Hz session
}  // namespace

TEST_CASE("keyboard: a press steps the throttle one level, even one shorter than a tick",
          "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardInterface kb(Config(), k.box, 8);
  CHECK(kb.Update(0.0, {}, hal).left == 0.0);

  k.Down(&InputState::key_up, &InputState::presses_up);
  TreadCommand m = kb.Update(kTick, {}, hal);
  CHECK(kb.throttle_level() == 1);
  CHECK(m.left == Approx(1.0 / 8));
  CHECK(m.right == Approx(1.0 / 8));
  // Held, but not yet for repeat_s: no second step.
  kb.Update(2 * kTick, {}, hal);
  CHECK(kb.throttle_level() == 1);
  k.Up(&InputState::key_up);

  SECTION("a tap between two ticks is carried by the next tick's command") {
    kb.Update(3 * kTick, {}, hal);
    CHECK(kb.throttle_level() == 0);  // released: back to zero
    k.Tap(&InputState::key_up, &InputState::presses_up);
    m = kb.Update(4 * kTick, {}, hal);
    CHECK(kb.throttle_level() == 1);
    CHECK(m.left == Approx(1.0 / 8));
    kb.Update(5 * kTick, {}, hal);
    CHECK(kb.throttle_level() == 0);
  }
  SECTION("two taps within one tick step twice") {
    KeyboardConfig keep = Config();
    keep.release_to_zero = false;
    KeyboardInterface kb2(keep, k.box, 8);
    k.Tap(&InputState::key_down, &InputState::presses_down);
    k.Tap(&InputState::key_down, &InputState::presses_down);
    kb2.Update(0.0, {}, hal);
    CHECK(kb2.throttle_level() == -2);
  }
}

TEST_CASE("keyboard: a held key repeats every repeat_s and levels clamp at the vehicle's",
          "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardInterface kb(Config(), k.box, 8);
  k.Down(&InputState::key_up, &InputState::presses_up);
  kb.Update(1.0, {}, hal);
  CHECK(kb.throttle_level() == 1);
  kb.Update(1.0 + 0.11, {}, hal);
  CHECK(kb.throttle_level() == 1);
  kb.Update(1.0 + 0.121, {}, hal);
  CHECK(kb.throttle_level() == 2);
  kb.Update(1.0 + 0.235, {}, hal);
  CHECK(kb.throttle_level() == 2);
  kb.Update(1.0 + 0.245, {}, hal);
  CHECK(kb.throttle_level() == 3);
  // A slow session (one tick over three periods) still ramps by time.
  kb.Update(1.0 + 0.65, {}, hal);  // repeats due at 1.36, 1.48 and 1.60 all step
  CHECK(kb.throttle_level() == 6);
  // Held for long: clamps at +8, the vehicle's levels.
  for (double t = 1.67; t < 4.0; t += kTick) kb.Update(t, {}, hal);
  CHECK(kb.throttle_level() == 8);
  CHECK(kb.Update(4.0, {}, hal).left == Approx(1.0));
  // Extra presses past the top do not wind up beyond it.
  for (int i = 0; i < 5; ++i) k.Down(&InputState::key_up, &InputState::presses_up);
  kb.Update(4.02, {}, hal);
  CHECK(kb.throttle_level() == 8);

  k.Up(&InputState::key_up);
  SECTION("release returns to zero") {
    kb.Update(4.04, {}, hal);
    CHECK(kb.throttle_level() == 0);
  }
  SECTION("down from zero clamps at -8") {
    kb.Update(4.04, {}, hal);
    k.Down(&InputState::key_down, &InputState::presses_down);
    for (double t = 4.06; t < 8.0; t += kTick) kb.Update(t, {}, hal);
    CHECK(kb.throttle_level() == -8);
    const TreadCommand m = kb.Update(8.0, {}, hal);
    CHECK(m.left == Approx(-1.0));
    CHECK(m.right == Approx(-1.0));
  }
}

TEST_CASE("keyboard: without release_to_zero a level stays when the keys are released",
          "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardConfig c = Config();
  c.release_to_zero = false;
  KeyboardInterface kb(c, k.box, 8);
  k.Tap(&InputState::key_up, &InputState::presses_up);
  k.Tap(&InputState::key_up, &InputState::presses_up);
  kb.Update(0.0, {}, hal);
  kb.Update(1.0, {}, hal);
  CHECK(kb.throttle_level() == 2);
}

TEST_CASE("keyboard: space stops both levels at once", "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardConfig c = Config();
  c.release_to_zero = false;
  KeyboardInterface kb(c, k.box, 8);
  for (int i = 0; i < 3; ++i) k.Tap(&InputState::key_up, &InputState::presses_up);
  for (int i = 0; i < 2; ++i) k.Tap(&InputState::key_right, &InputState::presses_right);
  kb.Update(0.0, {}, hal);
  REQUIRE(kb.throttle_level() == 3);
  REQUIRE(kb.steering_level() == -2);
  // Even a tap of space shorter than a tick.
  k.Tap(&InputState::key_stop, &InputState::presses_stop);
  const TreadCommand m = kb.Update(kTick, {}, hal);
  CHECK(kb.throttle_level() == 0);
  CHECK(kb.steering_level() == 0);
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
}

TEST_CASE("keyboard: the left key turns left (right motor faster than left)", "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardConfig c = Config();
  c.release_to_zero = false;
  KeyboardInterface kb(c, k.box, 8);
  for (int i = 0; i < 4; ++i) k.Tap(&InputState::key_up, &InputState::presses_up);
  for (int i = 0; i < 4; ++i) k.Tap(&InputState::key_left, &InputState::presses_left);
  const TreadCommand m = kb.Update(0.0, {}, hal);
  CHECK(kb.steering_level() == 4);
  // forward 4/8, turn 0.5 × 4/8: left = 0.5 − 0.25, right = 0.5 + 0.25.
  CHECK(m.left == Approx(0.25));
  CHECK(m.right == Approx(0.75));
  for (int i = 0; i < 8; ++i) k.Tap(&InputState::key_right, &InputState::presses_right);
  const TreadCommand r = kb.Update(kTick, {}, hal);
  CHECK(kb.steering_level() == -4);
  CHECK(r.left > r.right);
}

TEST_CASE("keyboard: presses made before the interface existed are not replayed", "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  for (int i = 0; i < 3; ++i) k.Tap(&InputState::key_up, &InputState::presses_up);
  KeyboardInterface kb(Config(), k.box, 8);
  kb.Update(0.0, {}, hal);
  CHECK(kb.throttle_level() == 0);
}

TEST_CASE(
    "keyboard: taken up again (a fleet's other vehicle was driven meanwhile), it starts from rest "
    "and replays "
    "none of the presses made meanwhile",
    "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardConfig c = Config();
  c.release_to_zero = false;
  KeyboardInterface kb(c, k.box, 8);
  for (int i = 0; i < 2; ++i) k.Tap(&InputState::key_up, &InputState::presses_up);
  kb.Update(0.0, {}, hal);
  REQUIRE(kb.throttle_level() == 2);  // left at level 2 when the person turned away
  // Meanwhile the same keys drove another vehicle.
  for (int i = 0; i < 3; ++i) k.Tap(&InputState::key_up, &InputState::presses_up);
  k.Tap(&InputState::key_left, &InputState::presses_left);
  kb.Rebase(k.box.Load());
  const TreadCommand m = kb.Update(1.0, {}, hal);
  CHECK(kb.throttle_level() == 0);
  CHECK(kb.steering_level() == 0);
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
  // A press from now on is its own again.
  k.Tap(&InputState::key_up, &InputState::presses_up);
  kb.Update(1.0 + kTick, {}, hal);
  CHECK(kb.throttle_level() == 1);
}

TEST_CASE("keyboard: no hands, no physics, no forces", "[keyboard]") {
  Keys k;
  haptics::Hal hal;
  KeyboardInterface kb(Config(), k.box, 8);
  const HandTargets targets = kb.HandTargetsFor({0.5, 0.2});
  CHECK_FALSE(targets[0].has_value());
  CHECK_FALSE(targets[1].has_value());
  CHECK_FALSE(kb.NeedsPhysics());
  CHECK(kb.name() == "keyboard");
  kb.Update(0.0, {}, hal);
  for (int side = 0; side < haptics::kSides; ++side) {
    CHECK_FALSE(hal.Setpoint(static_cast<haptics::Side>(side)).field.enabled);
  }
  CHECK_THROWS_AS(KeyboardInterface(Config(), k.box, 0), std::invalid_argument);
}

TEST_CASE("keyboard: refuses a config KeyboardConfig::ValidateOrThrow refuses") {
  Keys k;
  KeyboardConfig c = Config();
  c.turn_share = 1.5;
  CHECK_THROWS_WITH(KeyboardInterface(c, k.box, 8),
                    Catch::Contains("turn_share: expected a number in [0, 1]"));
  CHECK_THROWS_AS(KeyboardInterface(c, k.box, 8), ConfigFieldError);
}
