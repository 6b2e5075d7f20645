#pragma once
/// @file The keyboard interface: the thesis's practice-lap remote control
/// (ch. 8.1.2), a PC whose arrow keys step the throttle and the steering.
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"

namespace haptel {

struct KeyboardConfig {
  std::filesystem::path file;
  std::string name = "keyboard";
  /// A held up/down/left/right key steps its level again this often, s. The
  /// first repeat comes `repeat_s` after the press, like a typematic key.
  double repeat_s = 0.12;
  /// Releasing both throttle (both steering) keys returns the throttle
  /// (steering) to level 0; false keeps the level, as a real R/C remote trim.
  bool release_to_zero = true;
  double turn_share = 0.7;  ///< how much of the motor range turning may take
  double command_rate_hz = 50.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(name), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(repeat_s), config::Range{0.01, 2.0});
    a->Visit(HAPTEL_NVP(release_to_zero));
    a->Visit(HAPTEL_NVP(turn_share), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(command_rate_hz), config::Range{1.0, 1000.0});
  }

  /// Throws ConfigFieldError unless the name is set and every value is in range.
  void ValidateOrThrow() const;
};

/// Loads and validates (KeyboardConfig::ValidateOrThrow). Strict: unknown
/// keys are errors naming the file, the key and the line.
KeyboardConfig LoadKeyboard(const std::filesystem::path& file);

}  // namespace haptel
