// The keyboard and gamepad interface configs: the shipped files load with the
// values they say; a bad file is a ConfigError naming file, line and key.
// Runs from the repository root (ctest sets the working directory).
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/gamepad.hpp"
#include "haptel/config/keyboard.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::ConfigError;

namespace {
fs::path Write(const std::string& name, const std::string& text) {
  static const fs::path dir = haptel::test::ScratchDir("test_input_config");
  return haptel::test::WriteFile(dir / name, text);
}
template <typename F>
std::string ErrorOf(F&& f) {
  return haptel::test::WhatOf<ConfigError>(std::forward<F>(f));
}
}  // namespace

TEST_CASE("shipped keyboard.yaml loads with its values", "[config][shipped][keyboard]") {
  const haptel::KeyboardConfig k = haptel::LoadKeyboard("config/interfaces/keyboard.yaml");
  CHECK(k.name == "keyboard");
  CHECK(k.repeat_s == Approx(0.12));
  CHECK(k.release_to_zero);
  CHECK(k.turn_share == Approx(0.7));
  CHECK(k.command_rate_hz == Approx(50));
}

TEST_CASE("shipped gamepad.yaml loads with its values", "[config][shipped][gamepad]") {
  const haptel::GamepadConfig g = haptel::LoadGamepad("config/interfaces/gamepad.yaml");
  CHECK(g.name == "gamepad");
  CHECK(g.dead_zone == Approx(0.12));
  CHECK(g.trigger_dead_zone == Approx(0.05));
  CHECK(g.turn_axis == haptel::GamepadTurnAxis::kLeftX);
  CHECK(g.turn_share == Approx(0.7));
  CHECK(g.deadman == haptel::GamepadDeadman::kLeftShoulder);
}

TEST_CASE("keyboard and gamepad files: absent keys take the defaults",
          "[config][keyboard][gamepad]") {
  const haptel::KeyboardConfig k =
      haptel::LoadKeyboard(Write("k.yaml", "name: keyboard\nrepeat_s: 0.2\n"));
  CHECK(k.repeat_s == Approx(0.2));
  CHECK(k.release_to_zero == haptel::KeyboardConfig{}.release_to_zero);
  const haptel::GamepadConfig g =
      haptel::LoadGamepad(Write("g.yaml", "name: gamepad\nturn_axis: right_x\ndeadman: none\n"));
  CHECK(g.turn_axis == haptel::GamepadTurnAxis::kRightX);
  CHECK(g.deadman == haptel::GamepadDeadman::kNone);
  CHECK(g.dead_zone == haptel::GamepadConfig{}.dead_zone);
}

TEST_CASE("keyboard and gamepad files: bad keys and values name file, line and key",
          "[config][keyboard][gamepad]") {
  SECTION("unknown keyboard key") {
    const fs::path f = Write("k1.yaml", "name: keyboard\nrepeat_s: 0.1\nrepaet: 3\n");
    const std::string msg = ErrorOf([&] { haptel::LoadKeyboard(f); });
    CHECK_THAT(msg, Contains(f.string()));
    CHECK_THAT(msg, Contains("repaet"));
    CHECK_THAT(msg, Contains(":3:"));
  }
  SECTION("keyboard repeat out of range") {
    const fs::path f = Write("k2.yaml", "name: keyboard\nrepeat_s: 0\n");
    const std::string msg = ErrorOf([&] { haptel::LoadKeyboard(f); });
    CHECK_THAT(msg, Contains("'repeat_s'"));
    CHECK_THAT(msg, Contains(":2:"));
  }
  SECTION("keyboard file named as another interface") {
    const fs::path f = Write("k3.yaml", "name: gesture\n");
    CHECK_THAT(ErrorOf([&] { haptel::LoadKeyboard(f); }), Contains("'name'"));
  }
  SECTION("unknown deadman button lists the choices") {
    const fs::path f = Write("g1.yaml", "name: gamepad\ndeadman: start\n");
    const std::string msg = ErrorOf([&] { haptel::LoadGamepad(f); });
    CHECK_THAT(msg, Contains(f.string()));
    CHECK_THAT(msg, Contains("'deadman'"));
    CHECK_THAT(msg, Contains(":2:"));
    CHECK_THAT(msg, Contains("left_shoulder"));
  }
  SECTION("unknown turn axis") {
    const fs::path f = Write("g2.yaml", "name: gamepad\nturn_axis: left_y\n");
    const std::string msg = ErrorOf([&] { haptel::LoadGamepad(f); });
    CHECK_THAT(msg, Contains("'turn_axis'"));
    CHECK_THAT(msg, Contains("right_x"));
  }
  SECTION("unknown gamepad key") {
    const fs::path f = Write("g3.yaml", "name: gamepad\ndeadzone: 0.1\n");
    const std::string msg = ErrorOf([&] { haptel::LoadGamepad(f); });
    CHECK_THAT(msg, Contains("deadzone"));
    CHECK_THAT(msg, Contains(":2:"));
  }
  SECTION("gamepad dead zone out of range") {
    const fs::path f = Write("g4.yaml", "name: gamepad\ndead_zone: 1.5\n");
    CHECK_THAT(ErrorOf([&] { haptel::LoadGamepad(f); }), Contains("'dead_zone'"));
  }
}
