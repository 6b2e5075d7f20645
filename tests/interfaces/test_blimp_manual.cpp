#include <catch2/catch.hpp>
#include <filesystem>

#include "alloc_counter.hpp"
#include "haptel/config/error.hpp"
#include "haptel/interfaces/blimp_manual.hpp"
#include "haptel/interfaces/gamepad.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::interfaces;

namespace {

BlimpManualConfig KeysConfig() {
  BlimpManualConfig c;
  c.name = "blimp-keys";
  c.power_steps = 10;
  c.helix_steps = 4;
  c.elevator_steps = 4;
  c.repeat_s = 0.15;
  c.rudder_rate = 3.0;
  return c;
}

BlimpManualConfig PadConfig() {
  BlimpManualConfig c;
  c.name = "blimp-gamepad";
  c.dead_zone = 0.1;
  c.trigger_dead_zone = 0.05;
  return c;
}

/// What the input thread publishes, one physical key at a time.
struct Keys {
  InputState s;
  void Down(Key k) {
    s.keys_held[static_cast<size_t>(k)] = true;
    ++s.key_presses[static_cast<size_t>(k)];
  }
  void Up(Key k) { s.keys_held[static_cast<size_t>(k)] = false; }
  void Tap(Key k) {
    Down(k);
    Up(k);
  }
};

double& AxisOf(InputState& s, PadAxis a) { return s.pad_axes[static_cast<size_t>(a)]; }

constexpr double kTick = 0.02;  // a 50 Hz session

}  // namespace

TEST_CASE("blimp keys: W/S step the power, which stays where it is put", "[blimp_manual]") {
  Keys k;
  BlimpManualInterface m(KeysConfig(), k.s);
  CHECK(m.Step(0.0, k.s).power == 0.0);
  for (int i = 0; i < 3; ++i) k.Tap(Key::kW);
  CHECK(m.Step(kTick, k.s).power == Approx(0.3));
  CHECK(m.Step(2 * kTick, k.s).power == Approx(0.3));  // released: it stays
  k.Tap(Key::kS);
  CHECK(m.Step(3 * kTick, k.s).power == Approx(0.2));
  for (int i = 0; i < 5; ++i) k.Tap(Key::kS);
  CHECK(m.Step(4 * kTick, k.s).power == 0.0);  // never below none

  SECTION("a held W repeats every repeat_s, up to full power") {
    k.Down(Key::kW);
    CHECK(m.Step(5 * kTick, k.s).power == Approx(0.1));
    CHECK(m.Step(5 * kTick + 0.14, k.s).power == Approx(0.1));
    CHECK(m.Step(5 * kTick + 0.16, k.s).power == Approx(0.2));
    CHECK(m.Step(5 * kTick + 10.0, k.s).power == Approx(1.0));
  }
}

TEST_CASE(
    "blimp keys: arrows tilt the helix plane, page up/down trim the elevator, each on its own",
    "[blimp_manual]") {
  Keys k;
  BlimpManualInterface m(KeysConfig(), k.s);
  k.Tap(Key::kArrowUp);
  k.Tap(Key::kArrowUp);
  BlimpCommand c = m.Step(0.0, k.s);
  CHECK(c.helix == Approx(0.5));
  CHECK(c.power == 0.0);  // the arrows are not W (the robot's keyboard reads both as "up")
  CHECK(c.elevator == 0.0);
  for (int i = 0; i < 9; ++i) k.Tap(Key::kArrowDown);
  k.Tap(Key::kPageUp);
  c = m.Step(kTick, k.s);
  CHECK(c.helix == Approx(-1.0));  // clamped at full tilt down
  CHECK(c.elevator == Approx(0.25));
  k.Tap(Key::kPageDown);
  k.Tap(Key::kPageDown);
  CHECK(m.Step(2 * kTick, k.s).elevator == Approx(-0.25));
}

TEST_CASE("blimp keys: A/D swing the rudder while held, the tail rotor at zero power",
          "[blimp_manual]") {
  Keys k;
  BlimpManualInterface m(KeysConfig(), k.s);
  m.Step(0.0, k.s);
  SECTION("zero power: the tail rotor turns, the rudder stays centred (the quick turnabout)") {
    k.Down(Key::kA);
    BlimpCommand c = m.Step(0.1, k.s);
    CHECK(c.tail_rotor == Approx(0.3));  // 3 full deflections per second × 0.1 s; + is left
    CHECK(c.rudder == 0.0);
    c = m.Step(1.0, k.s);
    CHECK(c.tail_rotor == Approx(1.0));
    k.Up(Key::kA);
    CHECK(m.Step(1.2, k.s).tail_rotor == Approx(0.4));  // back at the same rate
    CHECK(m.Step(2.0, k.s).tail_rotor == 0.0);
  }
  SECTION("with power the same keys move the rudder; right arrow is right") {
    k.Tap(Key::kW);
    m.Step(0.0, k.s);
    k.Down(Key::kArrowRight);
    BlimpCommand c = m.Step(0.2, k.s);
    CHECK(c.rudder == Approx(-0.6));
    CHECK(c.tail_rotor == 0.0);
    k.Down(Key::kA);  // both ways at once: back to centre
    CHECK(m.Step(0.3, k.s).rudder == Approx(-0.3));
  }
}

TEST_CASE("blimp keys: space puts everything to neutral; presses before the start are not replayed",
          "[blimp_manual]") {
  Keys k;
  for (int i = 0; i < 4; ++i) k.Tap(Key::kW);  // made before the interface existed
  BlimpManualInterface m(KeysConfig(), k.s);
  CHECK(m.Step(0.0, k.s).power == 0.0);
  for (int i = 0; i < 5; ++i) k.Tap(Key::kW);
  k.Tap(Key::kArrowUp);
  k.Tap(Key::kPageUp);
  k.Down(Key::kD);
  BlimpCommand c = m.Step(0.5, k.s);
  REQUIRE(c.power == Approx(0.5));
  REQUIRE(c.rudder < 0.0);
  k.s.key_stop = true;
  ++k.s.presses_stop;
  c = m.Step(0.52, k.s);
  CHECK(c.power == 0.0);
  CHECK(c.helix == 0.0);
  CHECK(c.elevator == 0.0);
  CHECK(c.rudder == 0.0);
  CHECK(c.tail_rotor == 0.0);
}

TEST_CASE("blimp manual: the camera follows the head, clamped to the camera's range",
          "[blimp_manual]") {
  Keys k;
  BlimpManualInterface m(KeysConfig(), k.s);
  k.s.head_pan = 0.7;
  k.s.head_tilt = -0.3;
  BlimpCommand c = m.Step(0.0, k.s);
  CHECK(c.camera_pan == 0.7);
  CHECK(c.camera_tilt == -0.3);
  k.s.head_tilt = -3.0;
  CHECK(m.Step(kTick, k.s).camera_tilt == Approx(-kBlimpCameraTiltMax));
}

TEST_CASE("blimp gamepad: sticks and triggers map as the gesture cockpit's hands",
          "[blimp_manual]") {
  InputState s;
  s.pad_connected = true;
  BlimpManualInterface m(PadConfig(), s);
  CHECK(m.Step(0.0, s).power == 0.0);

  AxisOf(s, PadAxis::kLeftY) = -1.0;  // left stick up: full power
  AxisOf(s, PadAxis::kLeftX) = -0.5;  // sideways with power: nothing
  BlimpCommand c = m.Step(kTick, s);
  CHECK(c.power > 0.85);
  CHECK(c.tail_rotor == 0.0);

  AxisOf(s, PadAxis::kLeftY) = 0.8;   // pulled back: no power, never reverse
  AxisOf(s, PadAxis::kLeftX) = -1.0;  // so sideways is the tail rotor: left
  c = m.Step(2 * kTick, s);
  CHECK(c.power == 0.0);
  CHECK(c.tail_rotor > 0.5);

  AxisOf(s, PadAxis::kLeftY) = 0.0;
  AxisOf(s, PadAxis::kLeftX) = 0.0;
  AxisOf(s, PadAxis::kRightX) = 1.0;  // right: rudder right (negative)
  AxisOf(s, PadAxis::kRightY) = 0.0;
  AxisOf(s, PadAxis::kTriggerRight) = 1.0;
  c = m.Step(3 * kTick, s);
  CHECK(c.rudder == Approx(-1.0));
  CHECK(c.helix == Approx(1.0));  // right trigger: the plane tilts up, to climb
  AxisOf(s, PadAxis::kRightX) = 0.0;
  AxisOf(s, PadAxis::kRightY) = 1.0;  // pulled back: nose up
  AxisOf(s, PadAxis::kTriggerRight) = 0.0;
  AxisOf(s, PadAxis::kTriggerLeft) = 1.0;
  c = m.Step(4 * kTick, s);
  CHECK(c.elevator == Approx(1.0));
  CHECK(c.helix == Approx(-1.0));

  AxisOf(s, PadAxis::kRightY) = 0.05;  // inside the dead zone
  AxisOf(s, PadAxis::kTriggerLeft) = 0.03;
  c = m.Step(5 * kTick, s);
  CHECK(c.elevator == 0.0);
  CHECK(c.helix == 0.0);
}

TEST_CASE("blimp gamepad: no controller, or one that went away, flies nothing", "[blimp_manual]") {
  InputState s;
  BlimpManualInterface m(PadConfig(), s);
  AxisOf(s, PadAxis::kLeftY) = -1.0;
  CHECK(m.Step(0.0, s).power == 0.0);  // not connected yet: the person is told
  REQUIRE(m.Notice() != nullptr);
  CHECK(std::string(m.Notice()) == kNoControllerNotice);
  s.pad_connected = true;
  CHECK(m.Step(kTick, s).power > 0.8);
  CHECK(m.Notice() == nullptr);
  CHECK_FALSE(m.lost());
  s.pad_connected = false;
  ++s.pad_disconnects;
  CHECK(m.Step(2 * kTick, s).power == 0.0);
  CHECK(m.lost());
  s.pad_connected = true;  // plugged back in: still lost, the run ends
  CHECK(m.Step(3 * kTick, s).power == 0.0);
  CHECK(m.lost());
}

TEST_CASE("blimp manual: a step allocates nothing", "[blimp_manual][alloc]") {
  Keys k;
  BlimpManualInterface keys(KeysConfig(), k.s);
  InputState pad;
  pad.pad_connected = true;
  BlimpManualInterface stick(PadConfig(), pad);
  haptics::Hal hal;
  const uint64_t before = haptel::test::ThreadAllocations();
  double sum = 0.0;
  for (int i = 0; i < 1000; ++i) {
    k.Tap(i % 3 == 0 ? Key::kW : Key::kArrowUp);
    sum += keys.Update(i * kTick, k.s, hal).power;
    AxisOf(pad, PadAxis::kLeftY) = -0.001 * i;
    sum += stick.Update(i * kTick, pad, hal).power;
  }
  CHECK(haptel::test::ThreadAllocations() == before);
  CHECK(sum > 0.0);
}

TEST_CASE(
    "blimp manual: the shipped files load; a key of the other input or a bad value is refused by "
    "name",
    "[blimp_manual][config]") {
  const BlimpManualConfig keys = LoadBlimpManual("config/interfaces/blimp-keys.yaml");
  CHECK(keys.input() == BlimpManualInput::kKeys);
  CHECK(keys.power_steps == 10);
  const BlimpManualConfig pad = LoadBlimpManual("config/interfaces/blimp-gamepad.yaml");
  CHECK(pad.input() == BlimpManualInput::kGamepad);

  const std::filesystem::path dir = haptel::test::ScratchDir("blimp_manual");
  const auto write = [&](const std::string& text) {
    return haptel::test::WriteFile(dir / "blimp-keys.yaml", text);
  };
  CHECK_THROWS_WITH(LoadBlimpManual(write("name: blimp-keys\ndead_zone: 0.1\n")),
                    Catch::Contains("dead_zone") && Catch::Contains("blimp-keys.yaml"));
  CHECK_THROWS_WITH(LoadBlimpManual(write("name: blimp-keys\npower_steps: 0\n")),
                    Catch::Contains("power_steps"));
  CHECK_THROWS_WITH(LoadBlimpManual(write("name: blimp-pedals\n")),
                    Catch::Contains("blimp-gamepad"));
  BlimpManualConfig bad = KeysConfig();
  bad.rudder_rate = 0.0;
  CHECK_THROWS_WITH(BlimpManualInterface(bad, InputState{}), Catch::Contains("rudder_rate"));
}
