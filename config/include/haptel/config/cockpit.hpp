#pragma once
/// @file The cockpit family of mediator interfaces: a steering wheel and a
/// throttle lever the hands touch and grasp (config/interfaces/cockpit*.yaml).
///
/// `cockpit` is the plain wheel and throttle; `cockpit-hud` adds a speedometer
/// and turn indicators; `cockpit-assisted` adds return-to-zero springs that
/// act while a control is released; `cockpit-shared` adds haptic shared
/// control (shared_control.hpp) acting on the wheel and the lever.
#include <array>
#include <filesystem>
#include <string>

#include "haptel/config/shared_control.hpp"

namespace haptel {

struct CockpitConfig {
  std::filesystem::path file;
  std::string name = "cockpit";
  bool hud = false;             ///< speedometer and turn indicators
  bool return_to_zero = false;  ///< controls spring back to zero when released

  /// Steering wheel: a rim on a hinge whose axis points at the driver.
  std::array<double, 3> wheel_hub{0.05, 0.0, 0.0};  ///< m, device frame
  double wheel_radius = 0.12;                       ///< m
  double wheel_max_angle_deg = 135;                 ///< hinge end stops, ±
  double wheel_full_turn_deg = 90;                  ///< angle giving the full turn command

  /// Throttle lever: a slider along x (forward = faster).
  std::array<double, 3> throttle_centre{0.05, -0.25, -0.05};  ///< m, device frame
  double throttle_travel = 0.06;                              ///< m from centre to each end stop

  double turn_share = 0.7;  ///< share of the motor range turning may take

  /// On a bumper contact: the wheel shakes, the throttle locks at zero.
  double shake_s = 0.6;
  double shake_torque = 0.3;  ///< N·m amplitude
  double shake_hz = 12.0;
  double throttle_lock_s = 1.0;

  /// Return-to-zero springs (cockpit-assisted), acting while released.
  double wheel_return_stiffness = 0.6;      ///< N·m/rad
  double throttle_return_stiffness = 60.0;  ///< N/m

  double command_rate_hz = 50.0;

  /// cockpit-shared's: a torque on the wheel away from a steer that leads
  /// into an obstacle and a force on the lever towards slower, in physics;
  /// disabled for the others.
  SharedControlConfig shared_control;

  /// Throws ConfigFieldError (keys as in the file: "wheel.radius") unless the
  /// name is set, every value is in range and full_turn_deg <= max_angle_deg < 180
  /// (and, for cockpit-shared, its shared_control section's).
  void ValidateOrThrow() const;
};

/// Loads and validates (CockpitConfig::ValidateOrThrow) a cockpit interface
/// file (strict: unknown keys are errors naming file, key and line).
CockpitConfig LoadCockpit(const std::filesystem::path& file);

}  // namespace haptel
