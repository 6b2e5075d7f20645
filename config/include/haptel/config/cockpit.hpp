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

#include "haptel/config/archive.hpp"
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

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::MakeNameValue, config::Range;
    a->Visit(HAPTEL_NVP(name), config::Required{}, config::NonEmpty{});
    a->Visit(HAPTEL_NVP(hud));
    a->Visit(HAPTEL_NVP(return_to_zero));
    a->Visit(HAPTEL_NVP(turn_share), Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(command_rate_hz), Range{1.0, 1000.0});
    a->Group("wheel", [this](auto* wheel) {
      wheel->Visit(MakeNameValue("hub", &wheel_hub), Range{-1.0, 1.0});
      wheel->Visit(MakeNameValue("radius", &wheel_radius), Range{0.03, 0.5});
      wheel->Visit(
          MakeNameValue("max_angle_deg", &wheel_max_angle_deg));  // [10, 180): ValidateOrThrow
      wheel->Visit(MakeNameValue("full_turn_deg", &wheel_full_turn_deg), Range{5.0, 720.0});
      wheel->Visit(MakeNameValue("return_stiffness", &wheel_return_stiffness), Range{0.0, 100.0});
    });
    a->Group("throttle", [this](auto* throttle) {
      throttle->Visit(MakeNameValue("centre", &throttle_centre), Range{-1.0, 1.0});
      throttle->Visit(MakeNameValue("travel", &throttle_travel), Range{0.01, 0.5});
      throttle->Visit(MakeNameValue("return_stiffness", &throttle_return_stiffness),
                      Range{0.0, 1e4});
    });
    a->Group("contact", [this](auto* contact) {
      contact->Visit(MakeNameValue("shake_s", &shake_s), Range{0.0, 10.0});
      contact->Visit(MakeNameValue("shake_torque", &shake_torque), Range{0.0, 10.0});
      contact->Visit(MakeNameValue("shake_hz", &shake_hz), Range{0.5, 100.0});
      contact->Visit(MakeNameValue("throttle_lock_s", &throttle_lock_s), Range{0.0, 30.0});
    });
    a->Visit(HAPTEL_NVP(shared_control), config::IfPresent{});
  }

  /// Throws ConfigFieldError (keys as in the file: "wheel.radius") unless the
  /// name is set, every value is in range and full_turn_deg <= max_angle_deg < 180
  /// (and, for cockpit-shared, its shared_control section's).
  void ValidateOrThrow() const;
};

/// Loads and validates (CockpitConfig::ValidateOrThrow) a cockpit interface
/// file (strict: unknown keys are errors naming file, key and line).
CockpitConfig LoadCockpit(const std::filesystem::path& file);

}  // namespace haptel
