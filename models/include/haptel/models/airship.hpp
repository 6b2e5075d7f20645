#pragma once
/// @file A 6-DoF airship: the thesis's R/C blimp as a rigid body in air.
///
/// In the spirit of Li & Nahon (2007) and gz-sim's lighter-than-air plugin:
/// Kirchhoff's equations with added mass and inertia (Lamb's factors for a
/// prolate spheroid of the hull's fineness ratio), buoyancy at the centre of
/// buoyancy above the centre of gravity (the pendulum that rights roll and
/// pitch), hull axial drag and cross-flow drag, four tail fins whose lift
/// follows the dynamic pressure at the tail (with elevator and rudder), two
/// main propellers on a helix plane that tilts, and a reversible tail rotor.
///
/// Frames: the world is x east, y north, z up (the track's x, y plus
/// height); the body is x forward, y left, z up with its origin at the
/// centre of gravity. Yaw is counter-clockwise positive, like the robot's
/// heading (YawPitchRoll gives pitch nose-up positive).
///
/// Approximations, named: the added mass's inertia acts on the ground
/// acceleration, its Munk and Coriolis terms on the velocity through the
/// air (exact in still or steady air; a gust's own acceleration force is
/// left out);
/// the hull's rigid inertia is that of a solid spheroid of the whole mass;
/// the added-mass terms are taken about the centre of gravity.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "haptel/config/airship.hpp"

namespace haptel::models {

/// What the actuators are told, in physical terms (the servo channels'
/// pulse widths mapped through the vehicle's own linkage).
struct AirshipControls {
  double elevator = 0.0;    ///< -1..1 of max_surface_deg; positive: nose up
  double rudder = 0.0;      ///< -1..1; positive: turn left
  double power = 0.0;       ///< 0..1 of max_thrust
  double helix = 0.0;       ///< -1..1 of max_helix_deg; positive: thrust tilts up
  double tail_rotor = 0.0;  ///< -1..1 of tail_thrust; positive: turn left
};

/// The model's state: the integrated variables, nothing derived.
struct AirshipState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< of the centre of gravity, world, m
  Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();  ///< body → world
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< ground velocity, body frame, m/s
  Eigen::Vector3d rates = Eigen::Vector3d::Zero();     ///< angular velocity, body frame, rad/s
  double thrust = 0.0;                                 ///< N, both main motors, as spun up
  double helix_rad = 0.0;                              ///< helix plane tilt, as slewed
  double tail = 0.0;  ///< N, the tail rotor's thrust (positive: turn left)
};

/// Quantities derived from the state and the constants.
struct AirshipMassProperties {
  double mass = 0.0;                                       ///< kg: structure, payload, helium
  double buoyancy = 0.0;                                   ///< N: displaced air's weight
  double weight = 0.0;                                     ///< N
  Eigen::Vector3d inertia_mass = Eigen::Vector3d::Zero();  ///< diag of M (mass + added mass), kg
  Eigen::Vector3d inertia_moment =
      Eigen::Vector3d::Zero();  ///< diag of J (inertia + added inertia), kg·m²
  double lamb_k1 = 0.0, lamb_k2 = 0.0, lamb_k_rot = 0.0;  ///< Lamb's factors used
};

/// An external load that depends on the state alone (contact with the
/// ground and buildings): evaluated inside the integrator's every
/// derivative evaluation, as stiff loads must be, not held over a step.
/// Implementations must be allocation-free and deterministic.
class AirshipContact {
 public:
  virtual ~AirshipContact() = default;
  /// Adds nothing when there is no contact; otherwise writes the body-frame
  /// force (N) and moment about the centre of gravity (N·m).
  virtual void Loads(const AirshipState& state, Eigen::Vector3d* force_body,
                     Eigen::Vector3d* moment_body) const = 0;
};

/// Lamb's added-mass factors of a prolate spheroid with this length/diameter
/// ratio (> 1): k1 axial, k2 transverse, k' rotational (about a transverse axis).
void LambFactors(double fineness, double* k1, double* k2, double* k_rot);

/// The attitude (body → world) of these yaw, pitch and roll (rad), as
/// Airship::YawPitchRoll gives them: yaw about the world's z, then pitch
/// nose up, then roll right side down.
Eigen::Quaterniond AttitudeFromYawPitchRoll(double yaw, double pitch, double roll);

class Airship {
 public:
  /// Validates `config` (ConfigFieldError). Starts at rest at the origin.
  explicit Airship(const AirshipConfig& config);

  /// Advances by dt seconds in equal steps of at most config.step_s, with
  /// the controls held. Allocation-free.
  void Advance(double dt, const AirshipControls& controls);
  /// One step of `step_s` with the configured integrator.
  void Step(double step_s, const AirshipControls& controls);

  const AirshipState& state() const { return state_; }
  void set_state(const AirshipState& state) { state_ = state; }
  /// The steady wind (world frame, m/s) in place of the config's: the
  /// operator's predictor flies the wind it estimates (blimp_predictor.hpp).
  void set_mean_wind(const Eigen::Vector3d& mean) {
    config_.wind.mean = {mean.x(), mean.y(), mean.z()};
  }
  double time_s() const { return time_s_; }
  const AirshipConfig& config() const { return config_; }
  const AirshipMassProperties& mass_properties() const { return mass_; }

  /// The wind at time t (world frame, m/s).
  Eigen::Vector3d Wind(double t_s) const;
  /// Airspeed: the velocity relative to the air, in the body frame.
  Eigen::Vector3d Airspeed() const;
  /// Kinetic energy (with the added mass) plus the potential energy of
  /// weight and buoyancy, J; conserved when aerodynamics and thrust are off.
  double Energy() const;
  /// Yaw (heading, counter-clockwise from +x), pitch (nose up positive) and
  /// roll (right wing down positive), rad.
  Eigen::Vector3d YawPitchRoll() const;
  /// Whether every state variable is finite.
  bool Finite() const;
  /// The external contact load added to the body loads in every derivative
  /// evaluation (null: none). Not owned: it must outlive its use here.
  void set_contact(const AirshipContact* contact) { contact_ = contact; }
  const AirshipContact* contact() const { return contact_; }

  /// Body-frame force and moment at a state (for tests and the integrators).
  void Loads(double t_s, const AirshipState& s, const AirshipControls& c, Eigen::Vector3d* force,
             Eigen::Vector3d* moment) const;

 private:
  struct Derivative {
    Eigen::Vector3d position_dot, velocity_dot, rates_dot;
    Eigen::Vector4d attitude_dot;  ///< of the quaternion's coefficients (x, y, z, w)
    double thrust_dot = 0.0, helix_dot = 0.0, tail_dot = 0.0;
  };
  Derivative Evaluate(double t_s, const AirshipState& s, const AirshipControls& c) const;
  static AirshipState Apply(const AirshipState& s, const Derivative& d, double h);

  AirshipConfig config_;
  AirshipMassProperties mass_;
  AirshipState state_;
  double time_s_ = 0.0;
  const AirshipContact* contact_ = nullptr;
  // Gust components: per axis, 6 sinusoids.
  static constexpr int kGustTerms = 6;
  /// The helix-plane servo follows its target with this lag, within its slew rate.
  static constexpr double kServoTimeConstant = 0.1;
  double gust_amplitude_[3][kGustTerms]{};
  double gust_omega_[kGustTerms]{};
  double gust_phase_[3][kGustTerms]{};
};

}  // namespace haptel::models
