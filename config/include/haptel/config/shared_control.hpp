#pragma once
/// @file Haptic shared control's settings (gesture-shared, cockpit-shared):
/// the `shared_control:` section of an interface file.
#include "haptel/config/archive.hpp"

namespace haptel {

/// Haptic shared control: a force that pushes the operator away from commands
/// whose predicted motion meets an obstacle the vehicle's range sensors see
/// within `horizon_s` (each command's path looked along at the hand's own
/// speed: steering away first, slowing down where no steer clears it), a
/// spring of `stiffness` past the safe commands' boundary, never above
/// `max_force`, so the operator can always push through. The commands
/// stay the operator's: the force and the operator's own push blend at the
/// hand (gesture-shared) or on the controls (cockpit-shared: the lever, and
/// the wheel's rim). No section (`enabled` false): the plain interface.
struct SharedControlConfig {
  bool enabled = false;
  double horizon_s = 1.0;  ///< s of predicted motion looked through
  double max_force =
      6.0;  ///< N: the most the guidance ever pushes (at the hand, the lever, the rim)
  double stiffness =
      600.0;  ///< N/m of travel (hand; lever; along the rim) past the safe commands' boundary
  double clearance = 0.03;  ///< m kept between the body and an obstacle (beyond its radius)

  template <typename Archive>
  void Serialize(Archive* a) {
    // `enabled` is not a key: the interface's name says it.
    a->Visit(HAPTEL_NVP(horizon_s), config::Range{0.1, 10.0});
    a->Visit(HAPTEL_NVP(max_force), config::Range{0.0, 15.0});
    a->Visit(HAPTEL_NVP(stiffness), config::Range{0.0, 2000.0});
    a->Visit(HAPTEL_NVP(clearance), config::Range{0.0, 1.0});
  }

  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

}  // namespace haptel
