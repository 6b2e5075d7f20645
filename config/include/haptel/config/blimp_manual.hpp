#pragma once
/// @file The blimp flown by a person's keys or game controller, for a pilot
/// without a haptic device (the gesture cockpit needs both arms).
///
/// Keys (`blimp-keys`, read in the view's window):
/// - W/S step the main power by 1/power_steps per press (0..1); it stays.
/// - ↑/↓ step the helix plane's tilt by 1/helix_steps (−1..1): up climbs.
/// - Page Up/Down step the elevator trim by 1/elevator_steps: up is nose up.
/// - A/D (or ←/→) swing the rudder towards full at rudder_rate while held,
///   and back to centre when let go; with the power at zero they drive the
///   tail rotor instead (the gesture cockpit's quick turnabout).
/// - Space: everything to neutral (power off, plane level, surfaces centred).
///
/// Game controller (`blimp-gamepad`):
/// - left stick up: main power (down gives none); left stick sideways at
///   zero power: the tail rotor
/// - right stick: elevator (pull back: nose up) and rudder
/// - right trigger tilts the helix plane up, left trigger down
///
/// Both: the mouse dragged in the window turns the head, and so the camera.
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"
#include "haptel/config/interface_kinds.hpp"

namespace haptel {

enum class BlimpManualInput { kKeys, kGamepad };

struct BlimpManualConfig {
  std::filesystem::path file;
  /// "blimp-keys" or "blimp-gamepad": which input flies.
  std::string name = "blimp-keys";
  // --- Keys ---
  int power_steps = 10;      ///< presses of W from no power to full
  int helix_steps = 4;       ///< presses of ↑ from a level helix plane to full tilt
  int elevator_steps = 4;    ///< presses of Page Up from centred to full elevator
  double repeat_s = 0.15;    ///< s: a held key steps again this often
  double rudder_rate = 3.0;  ///< full deflections per second the rudder (tail rotor) swings at
  // --- Game controller ---
  double dead_zone = 0.12;          ///< radial, fraction of each stick's full deflection
  double trigger_dead_zone = 0.05;  ///< fraction of a trigger's full pull
  double command_rate_hz = 50.0;

  /// Which input flies, as the interface table says of `name`.
  BlimpManualInput input() const {
    const InterfaceKindInfo* kind = FindInterfaceKind(name);
    return kind != nullptr && kind->input == InterfaceInput::kGamepad ? BlimpManualInput::kGamepad
                                                                      : BlimpManualInput::kKeys;
  }

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(name));
    // A file gives its own input's keys only (the others are unknown keys);
    // the checker holds a struct built in code to all of them.
    const bool reads = Archive::kReads;
    if (!reads || input() == BlimpManualInput::kKeys) {
      a->Visit(HAPTEL_NVP(power_steps), Range{1, 100});
      a->Visit(HAPTEL_NVP(helix_steps), Range{1, 100});
      a->Visit(HAPTEL_NVP(elevator_steps), Range{1, 100});
      a->Visit(HAPTEL_NVP(repeat_s), Range{0.01, 2.0});
      a->Visit(HAPTEL_NVP(rudder_rate), Range{0.1, 100.0});
    }
    if (!reads || input() == BlimpManualInput::kGamepad) {
      a->Visit(HAPTEL_NVP(dead_zone), Range{0.0, 0.9});
      a->Visit(HAPTEL_NVP(trigger_dead_zone), Range{0.0, 0.9});
    }
    a->Visit(HAPTEL_NVP(command_rate_hz), Range{1.0, 1000.0});
  }

  /// Throws ConfigFieldError naming the first field out of range.
  void ValidateOrThrow() const;
};

/// Loads and validates (BlimpManualConfig::ValidateOrThrow). Strict: unknown
/// keys, including the other input's, are errors naming file, key and line.
BlimpManualConfig LoadBlimpManual(const std::filesystem::path& file);

}  // namespace haptel
