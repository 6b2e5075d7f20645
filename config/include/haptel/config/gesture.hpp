#pragma once
/// @file The gesture interface: no controls, the right hand's offset drives.
#include <array>
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"
#include "haptel/config/shared_control.hpp"

namespace haptel {

struct GestureConfig {
  std::filesystem::path file;
  std::string name = "gesture";
  /// Right-hand neutral point in the device frame (x forward, y left, z up), m.
  std::array<double, 3> neutral{0.0, 0.0, 0.0};
  double dead_zone = 0.01;     ///< m of offset that does nothing
  double full_forward = 0.08;  ///< forward offset past the dead zone for full speed, m
  double full_turn = 0.08;     ///< sideways offset past the dead zone for full turn, m
  double turn_share = 0.7;     ///< how much of the motor range turning may take
  /// Centring field F = -(k + k2·|d|)·d − b·v: stronger with distance.
  double field_stiffness = 40.0;          ///< N/m
  double field_stiffness_growth = 300.0;  ///< N/m²
  double field_damping = 2.0;             ///< N·s/m
  double wall_stiffness = 1500.0;         ///< N/m
  double wall_release_s = 0.3;            ///< the wall stays this long after the contact clears
  double command_rate_hz = 50.0;
  SharedControlConfig shared_control;  ///< gesture-shared's; disabled for gesture

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(name), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(neutral), Range{-1.0, 1.0});
    a->Visit(HAPTEL_NVP(dead_zone), Range{0.0, 0.2});
    a->Visit(HAPTEL_NVP(full_forward), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(full_turn), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(turn_share), Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(field_stiffness), Range{0.0, 2000.0});
    a->Visit(HAPTEL_NVP(field_stiffness_growth), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(field_damping), Range{0.0, 200.0});
    a->Visit(HAPTEL_NVP(wall_stiffness), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(wall_release_s), Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(command_rate_hz), Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(shared_control), config::IfPresent{});
  }

  /// Throws ConfigFieldError unless the name is set and every value is in range.
  void ValidateOrThrow() const;
};

/// Loads and validates (GestureConfig::ValidateOrThrow) a gesture interface
/// file (strict: unknown keys are errors naming file, key and line).
GestureConfig LoadGesture(const std::filesystem::path& file);

}  // namespace haptel
