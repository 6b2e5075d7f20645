#pragma once
/// @file The blimp gesture cockpit (thesis ch. 8.2.2): both hands, no controls.
#include <array>
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"

namespace haptel {

/// Offsets are from each hand's neutral point, in that arm's device frame
/// (x forward, y left, z up), m. Past a dead zone, an offset of `full_*`
/// more gives full deflection.
///
/// - Right hand, the aerodynamic stabilisers: forward/back is the elevator
///   (forward pushes the nose down, as a stick does), left/right the rudder.
/// - Left hand, the engines: forward is main power (back gives none), up/down
///   tilts the helix plane. With zero power a sideways motion drives the
///   reversible tail rotor instead (the quick turnabout).
/// - A centring field on each hand, F = -(k + k2·|d|)·d − b·v, pulls it to
///   neutral (no power, straight ahead) and grows with the offset: the effort
///   tells the pilot how fast the blimp goes.
struct BlimpGestureConfig {
  std::filesystem::path file;
  std::string name = "blimp-gesture";
  std::array<double, 3> right_neutral{0.0, 0.0, 0.0};  ///< m, right arm's device frame
  std::array<double, 3> left_neutral{0.0, 0.0, 0.0};   ///< m, left arm's device frame
  double dead_zone = 0.01;                             ///< m of offset that does nothing
  double full_elevator = 0.08;                         ///< m: right hand forward/back
  double full_rudder = 0.08;                           ///< m: right hand sideways
  double full_power = 0.10;                            ///< m: left hand forward
  double full_helix = 0.06;                            ///< m: left hand up/down
  double full_tail = 0.08;                             ///< m: left hand sideways, at zero power
  double field_stiffness = 40.0;                       ///< N/m
  double field_stiffness_growth = 300.0;               ///< N/m²
  double field_damping = 2.0;                          ///< N·s/m
  double command_rate_hz = 50.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(name), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(right_neutral), Range{-1.0, 1.0});
    a->Visit(HAPTEL_NVP(left_neutral), Range{-1.0, 1.0});
    a->Visit(HAPTEL_NVP(dead_zone), Range{0.0, 0.2});
    a->Visit(HAPTEL_NVP(full_elevator), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(full_rudder), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(full_power), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(full_helix), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(full_tail), Range{0.005, 0.5});
    a->Visit(HAPTEL_NVP(field_stiffness), Range{0.0, 2000.0});
    a->Visit(HAPTEL_NVP(field_stiffness_growth), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(field_damping), Range{0.0, 200.0});
    a->Visit(HAPTEL_NVP(command_rate_hz), Range{1.0, 1000.0});
  }

  /// Throws ConfigFieldError naming the first field out of range.
  void ValidateOrThrow() const;
};

/// Loads and validates (BlimpGestureConfig::ValidateOrThrow) a blimp gesture
/// interface file (strict: unknown keys are errors naming file, key and line).
BlimpGestureConfig LoadBlimpGesture(const std::filesystem::path& file);

}  // namespace haptel
