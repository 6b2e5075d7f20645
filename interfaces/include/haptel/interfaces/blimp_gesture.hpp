#pragma once
/// @file The blimp gesture cockpit (thesis ch. 8.2.2): both hands, no
/// controls, and the pilot's head aims the camera.
///
/// The mapping and the fields are BlimpGestureConfig's. The camera's pan and
/// tilt are the operator's head orientation (the view's head input, or the
/// automatic pilot's gaze), passed through and clamped to the camera head's
/// range.
#include "haptel/config/blimp_gesture.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/blimp_interface.hpp"

namespace haptel::interfaces {

class BlimpGestureInterface final : public BlimpInterface {
 public:
  /// Validates `config` first (BlimpGestureConfig::ValidateOrThrow: ConfigFieldError).
  explicit BlimpGestureInterface(const BlimpGestureConfig& config);

  std::string name() const override { return config_.name; }

  /// The catalogue's Update: the hands and the head in `reading`, stamped its `now_ns`.
  BlimpCommand Update(double t_s, const BlimpReading& reading, haptics::Hal& hal) override;

  /// Session thread: reads both hands from the HAL, puts the centring fields
  /// in it and returns the command. A hand without a valid sample gives the
  /// neutral command and no forces (the device is not holding it). The
  /// fields are stamped `now_ns` (the HAL's clock: MonotonicNs, or a
  /// simulated clock that also drives the servo loop's Tick).
  BlimpCommand Update(const HeadDirection& head, haptics::Hal& hal, int64_t now_ns);
  /// Update stamped now.
  BlimpCommand Update(const HeadDirection& head, haptics::Hal& hal);

  /// Pure mapping from both hands' positions (and the head) to a command.
  BlimpCommand Map(const haptics::Vec3d& left, const haptics::Vec3d& right,
                   const HeadDirection& head) const;

  /// Where a pilot would hold their hands to give `command` (its camera
  /// angles are not the hands' business). Tail rotor commands need zero
  /// power: with power the left hand's sideways offset means nothing.
  HandTargets HandTargetsFor(const BlimpCommand& command) const override;

  const char* Help(bool /*switchable*/) const override {
    return "drag the mouse to look around, Home looks ahead, Esc ends";
  }

  /// The field on each hand (what Update puts in the HAL).
  const haptics::ForceField& field(haptics::Side side) const {
    return fields_[haptics::Index(side)];
  }

 private:
  BlimpGestureConfig config_;
  std::array<haptics::ForceField, haptics::kSides> fields_;
};

}  // namespace haptel::interfaces
