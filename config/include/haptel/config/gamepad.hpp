#pragma once
/// @file The gamepad interface: a game controller's sticks and triggers.
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"

namespace haptel {

/// Which stick steers.
enum class GamepadTurnAxis { kLeftX, kRightX };

/// The button that must be held to drive (teleop_twist_joy's enable_button).
enum class GamepadDeadman { kNone, kA, kB, kX, kY, kLeftShoulder, kRightShoulder };

struct GamepadConfig {
  std::filesystem::path file;
  std::string name = "gamepad";
  /// Radial dead zone of each stick, as a fraction of full deflection; past
  /// it the output is rescaled so it starts from 0 (no jump at the edge).
  double dead_zone = 0.12;
  /// A trigger pulled less than this fraction counts as released.
  double trigger_dead_zone = 0.05;
  GamepadTurnAxis turn_axis = GamepadTurnAxis::kLeftX;
  double turn_share = 0.7;  ///< how much of the motor range turning may take
  GamepadDeadman deadman = GamepadDeadman::kLeftShoulder;
  double command_rate_hz = 50.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    using Axis = GamepadTurnAxis;
    using Button = GamepadDeadman;
    a->Visit(HAPTEL_NVP(name), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(dead_zone), config::Range{0.0, 0.9});
    a->Visit(HAPTEL_NVP(trigger_dead_zone), config::Range{0.0, 0.9});
    a->Visit(HAPTEL_NVP(turn_axis),
             config::Choice<Axis>{{{Axis::kLeftX, "left_x"}, {Axis::kRightX, "right_x"}}});
    a->Visit(HAPTEL_NVP(turn_share), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(deadman),
             config::Choice<Button>{{{Button::kNone, "none"},
                                     {Button::kA, "a"},
                                     {Button::kB, "b"},
                                     {Button::kX, "x"},
                                     {Button::kY, "y"},
                                     {Button::kLeftShoulder, "left_shoulder"},
                                     {Button::kRightShoulder, "right_shoulder"}},
                                    "one of: a, b, x, y, left_shoulder, right_shoulder, none"});
    a->Visit(HAPTEL_NVP(command_rate_hz), config::Range{1.0, 1000.0});
  }

  /// Throws ConfigFieldError unless the name is set and every value is in range.
  void ValidateOrThrow() const;
};

/// Loads and validates (GamepadConfig::ValidateOrThrow). Strict: unknown
/// keys are errors naming the file, the key and the line.
GamepadConfig LoadGamepad(const std::filesystem::path& file);

}  // namespace haptel
