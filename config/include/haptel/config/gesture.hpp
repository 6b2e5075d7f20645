#pragma once
/// @file The gesture interface: no controls, the right hand's offset drives.
#include <array>
#include <filesystem>
#include <string>

namespace haptel {

/// Haptic shared control (gesture-shared): a force that pushes the hand away
/// from commands whose predicted motion meets an obstacle the vehicle's range
/// sensors see within `horizon_s`, growing as the time to collision shrinks
/// and never above `max_force`, so the operator can always push through. The
/// commands stay the hand's: the force and the operator's own push blend at
/// the hand. No section (`enabled` false): the plain gesture interface.
struct SharedControlConfig {
  bool enabled = false;
  double horizon_s = 1.0;     ///< s of predicted motion looked through
  double max_force = 3.0;     ///< N: the most the guidance ever pushes
  double stiffness = 150.0;   ///< N/m of hand travel past the safe commands' boundary
  double clearance = 0.03;    ///< m kept between the body and an obstacle (beyond its radius)

  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

struct GestureConfig {
  std::filesystem::path file;
  std::string name = "gesture";
  /// Right-hand neutral point in the device frame (x forward, y left, z up), m.
  std::array<double, 3> neutral{0.0, 0.0, 0.0};
  double dead_zone = 0.01;      ///< m of offset that does nothing
  double full_forward = 0.08;   ///< forward offset past the dead zone for full speed, m
  double full_turn = 0.08;      ///< sideways offset past the dead zone for full turn, m
  double turn_share = 0.7;      ///< how much of the motor range turning may take
  /// Centring field F = -(k + k2·|d|)·d − b·v: stronger with distance.
  double field_stiffness = 40.0;            ///< N/m
  double field_stiffness_growth = 300.0;    ///< N/m²
  double field_damping = 2.0;               ///< N·s/m
  double wall_stiffness = 1500.0;           ///< N/m
  double wall_release_s = 0.3;  ///< the wall stays this long after the contact clears
  double command_rate_hz = 50.0;
  SharedControlConfig shared_control;  ///< gesture-shared's; disabled for gesture

  /// Throws ConfigFieldError unless the name is set and every value is in range.
  void ValidateOrThrow() const;
};

/// Loads and validates (GestureConfig::ValidateOrThrow) a gesture interface
/// file (strict: unknown keys are errors naming file, key and line).
GestureConfig LoadGesture(const std::filesystem::path& file);

}  // namespace haptel
