#pragma once
/// @file The simulated airship's physical parameters (the `airship:` section
/// of a blimp vehicle file, config/vehicles/sim-blimp.yaml). Sized to the
/// thesis's R/C blimp (ch. 8.2.1): envelope 6.75 m × 2.2 m, 11 m³ of helium,
/// 9 kg all-up, two main motors of 1.5 kg thrust each, 35 km/h in still air.
#include <array>
#include <cstdint>
#include <string>

#include "haptel/config/archive.hpp"

namespace haptel {

/// Wind in the world frame (x east, y north, z up): a mean and gusts. The
/// gusts are a sum of sinusoids with random phases (fixed by the seed), so
/// the wind is a smooth, deterministic function of time that every
/// integrator and step size sees alike.
struct WindConfig {
  std::array<double, 3> mean{0.0, 0.0, 0.0};  ///< m/s
  double gust_rms = 0.0;     ///< m/s per horizontal axis (a third of it vertically)
  double gust_time_s = 8.0;  ///< period of the slowest gust component
  uint64_t seed = 1;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(mean), config::Range{-30.0, 30.0});
    a->Visit(HAPTEL_NVP(gust_rms), config::Range{0.0, 20.0});
    a->Visit(HAPTEL_NVP(gust_time_s), config::Range{0.1, 600.0});
    a->Visit(HAPTEL_NVP(seed), config::Range{0, 1 << 30});
  }

  void ValidateOrThrow() const;
  bool operator==(const WindConfig&) const = default;
};

/// How the airship model advances in time.
enum class AirshipIntegrator { kSemiImplicitEuler, kMidpoint, kRk4 };
/// "semi-implicit-euler", "midpoint", "rk4", as written in a file.
const char* AirshipIntegratorName(AirshipIntegrator integrator);
/// The integrator a name means; false when none does.
bool ParseAirshipIntegrator(const std::string& name, AirshipIntegrator* integrator);

struct AirshipConfig {
  // Hull: a prolate spheroid.
  double length = 6.75;            ///< m
  double diameter = 2.2;           ///< m
  double volume = 11.0;            ///< m³ of helium
  double air_density = 1.225;      ///< kg/m³ (ISA sea level)
  double helium_density = 0.1786;  ///< kg/m³
  double structure_mass = 9.0;     ///< kg: envelope, gondola, motors, batteries (all-up, thesis)
  /// kg: cameras, video link and ballast. 11 m³ lifts 11.51 kg net of its
  /// helium, so 2.55 kg over the 9 kg leaves the blimp 40 g heavy (the
  /// thesis: "around 2 kg of maximum payload").
  double payload_mass = 2.55;
  double cg_below_cb =
      0.5;  ///< m: the gondola hangs the centre of gravity below the centre of buoyancy

  // Aerodynamics.
  /// Hull axial drag coefficient on the volume-based area V^(2/3); 0.103 is
  /// fitted so that 2 × 1.5 kgf of thrust settles at 35 km/h (thesis).
  double axial_drag_coefficient = 0.103;
  /// Cross-flow drag coefficient of the hull (sideways and vertical motion,
  /// rotation), on the hull's side area π·L·D/4.
  double crossflow_drag_coefficient = 0.4;
  double fin_area = 0.6;        ///< m², each of four fins (cruciform tail)
  double fin_lift_slope = 3.0;  ///< per rad: a low-aspect-ratio fin
  double fin_arm = 2.9;  ///< m from the centre of gravity back to the fins' centre of pressure
  /// Lift per radian of surface deflection, as a fraction of the fin's lift slope.
  double control_effectiveness = 0.5;
  double max_surface_deg = 25.0;  ///< elevator and rudder travel
  /// The thesis: the stabilisers bite only above about 8 km/h. The fins'
  /// lift is scaled by V⁴/(V⁴ + V_on⁴), a smooth onset (our form: small
  /// surfaces in the hull's thick low-speed boundary layer).
  double fin_onset_speed = 2.2;  ///< m/s (8 km/h)

  // Propulsion.
  double max_thrust = 29.4;           ///< N, both main motors together (2 × 1.5 kgf, thesis)
  double thrust_time_constant = 0.5;  ///< s, motor and propeller spin-up
  double propeller_x = 0.3;           ///< m ahead of the centre of gravity
  double propeller_z = -0.15;         ///< m (below the centre of gravity: negative)
  double max_helix_deg = 90.0;        ///< helix plane tilt each way (up: climb)
  double helix_rate_deg_s = 90.0;     ///< the tilt servo's slew rate
  double tail_thrust = 2.0;           ///< N, the reversible tail rotor at full
  double tail_time_constant = 0.3;    ///< s
  double tail_arm = 3.0;              ///< m behind the centre of gravity (on the lower fin)
  double tail_z = -0.9;               ///< m

  WindConfig wind;

  // Numerics.
  AirshipIntegrator integrator = AirshipIntegrator::kRk4;
  double step_s = 0.005;  ///< integration step (substeps of the vehicle's tick)
  /// Off: no aerodynamic force at all (hull drag, fins) — for checking the
  /// conservative part of the model (energy), not for flying.
  bool aerodynamics = true;

  template <typename Archive>
  void Serialize(Archive* a) {
    // Every field but `aerodynamics` (a switch for tests, never in a file).
    using config::Range;
    a->Visit(HAPTEL_NVP(length), Range{0.1, 500.0});
    a->Visit(HAPTEL_NVP(diameter), Range{0.05, 100.0});
    a->Visit(HAPTEL_NVP(volume), Range{1e-3, 1e6});
    a->Visit(HAPTEL_NVP(air_density), Range{0.1, 2.0});
    a->Visit(HAPTEL_NVP(helium_density), Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(structure_mass), Range{0.01, 1e5});
    a->Visit(HAPTEL_NVP(payload_mass), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(cg_below_cb), Range{0.0, 50.0});
    a->Visit(HAPTEL_NVP(axial_drag_coefficient), Range{0.0, 5.0});
    a->Visit(HAPTEL_NVP(crossflow_drag_coefficient), Range{0.0, 5.0});
    a->Visit(HAPTEL_NVP(fin_area), Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(fin_lift_slope), Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(fin_arm), Range{0.0, 250.0});
    a->Visit(HAPTEL_NVP(control_effectiveness), Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(max_surface_deg), Range{0.0, 60.0});
    a->Visit(HAPTEL_NVP(fin_onset_speed), Range{0.01, 50.0});
    a->Visit(HAPTEL_NVP(max_thrust), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(thrust_time_constant), Range{0.01, 10.0});
    a->Visit(HAPTEL_NVP(propeller_x), Range{-250.0, 250.0});
    a->Visit(HAPTEL_NVP(propeller_z), Range{-50.0, 50.0});
    a->Visit(HAPTEL_NVP(max_helix_deg), Range{0.0, 120.0});
    a->Visit(HAPTEL_NVP(helix_rate_deg_s), Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(tail_thrust), Range{0.0, 1e4});
    a->Visit(HAPTEL_NVP(tail_time_constant), Range{0.01, 10.0});
    a->Visit(HAPTEL_NVP(tail_arm), Range{0.0, 250.0});
    a->Visit(HAPTEL_NVP(tail_z), Range{-50.0, 50.0});
    a->Visit(HAPTEL_NVP(wind));
    using Integrator = AirshipIntegrator;
    a->Visit(HAPTEL_NVP(integrator),
             config::Choice<Integrator>{{{Integrator::kSemiImplicitEuler, "semi-implicit-euler"},
                                         {Integrator::kMidpoint, "midpoint"},
                                         {Integrator::kRk4, "rk4"}}});
    a->Visit(HAPTEL_NVP(step_s), Range{1e-5, 0.1});
  }

  /// Throws ConfigFieldError naming the first field out of range.
  /// m/s: the airspeed at which both main motors at full thrust meet the
  /// hull's axial drag, ½·ρ·C·V^⅔·u² = max_thrust (the model's top speed in
  /// still air; 35 km/h for the thesis's blimp).
  double StillAirTopSpeed() const;

  void ValidateOrThrow() const;
  bool operator==(const AirshipConfig&) const = default;
};

}  // namespace haptel
