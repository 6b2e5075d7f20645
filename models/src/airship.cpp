#include "haptel/models/airship.hpp"

#include <algorithm>
#include <cmath>
#include <random>

namespace haptel::models {

namespace {

constexpr double kGravity = 9.80665;

/// Signed square: v|v| (drag opposes motion, grows with its square).
double SignedSquare(double v) { return v * std::abs(v); }

Eigen::Quaterniond Exp(const Eigen::Vector3d& rotation) {
  const double angle = rotation.norm();
  if (angle < 1e-12)
    return Eigen::Quaterniond(1.0, 0.5 * rotation.x(), 0.5 * rotation.y(), 0.5 * rotation.z())
        .normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation / angle));
}

}  // namespace

void LambFactors(double fineness, double* k1, double* k2, double* k_rot) {
  const double f = std::max(fineness, 1.0 + 1e-6);
  const double e = std::sqrt(1.0 - 1.0 / (f * f));
  const double e2 = e * e, e3 = e2 * e;
  const double log_term = std::log((1.0 + e) / (1.0 - e));
  const double alpha0 = 2.0 * (1.0 - e2) / e3 * (0.5 * log_term - e);
  const double beta0 = 1.0 / e2 - (1.0 - e2) / (2.0 * e3) * log_term;
  *k1 = alpha0 / (2.0 - alpha0);
  *k2 = beta0 / (2.0 - beta0);
  *k_rot = e2 * e2 * (beta0 - alpha0) / ((2.0 - e2) * (2.0 * e2 - (2.0 - e2) * (beta0 - alpha0)));
}

Eigen::Quaterniond AttitudeFromYawPitchRoll(double yaw, double pitch, double roll) {
  // Body y points left: a nose-up pitch is a negative turn about it.
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

Airship::Airship(const AirshipConfig& config) : config_(config) {
  config.ValidateOrThrow();
  const double a = config.length / 2.0, b = config.diameter / 2.0;
  AirshipMassProperties& m = mass_;
  m.mass = config.structure_mass + config.payload_mass + config.helium_density * config.volume;
  m.weight = m.mass * kGravity;
  m.buoyancy = config.air_density * config.volume * kGravity;
  LambFactors(config.length / config.diameter, &m.lamb_k1, &m.lamb_k2, &m.lamb_k_rot);
  const double air = config.air_density * config.volume;
  m.inertia_mass = {m.mass + m.lamb_k1 * air, m.mass + m.lamb_k2 * air, m.mass + m.lamb_k2 * air};
  const double transverse = 0.2 * (a * a + b * b);
  m.inertia_moment = {0.4 * m.mass * b * b, m.mass * transverse + m.lamb_k_rot * air * transverse,
                      m.mass * transverse + m.lamb_k_rot * air * transverse};

  // Gusts: sinusoids from the slowest period up, amplitudes falling as f^(-5/6)
  // (a von Kármán-like spectrum), scaled to the configured rms.
  std::mt19937_64 random(config.wind.seed);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  double sum_squares = 0.0;
  for (int k = 0; k < kGustTerms; ++k) {
    gust_omega_[k] = 2.0 * M_PI / config.wind.gust_time_s * std::pow(1.8, k);
    const double shape = std::pow(std::pow(1.8, k), -5.0 / 6.0);
    sum_squares += shape * shape / 2.0;
    for (int axis = 0; axis < 3; ++axis) {
      gust_amplitude_[axis][k] = shape;
      gust_phase_[axis][k] = phase(random);
    }
  }
  for (int axis = 0; axis < 3; ++axis) {
    const double rms = config.wind.gust_rms * (axis == 2 ? 1.0 / 3.0 : 1.0);
    for (double& amplitude : gust_amplitude_[axis]) amplitude *= rms / std::sqrt(sum_squares);
  }
}

Eigen::Vector3d Airship::Wind(double t_s) const {
  Eigen::Vector3d w(config_.wind.mean[0], config_.wind.mean[1], config_.wind.mean[2]);
  if (config_.wind.gust_rms > 0.0) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int k = 0; k < kGustTerms; ++k) {
        w[axis] += gust_amplitude_[axis][k] * std::sin(gust_omega_[k] * t_s + gust_phase_[axis][k]);
      }
    }
  }
  return w;
}

Eigen::Vector3d Airship::Airspeed() const {
  return state_.velocity - state_.attitude.conjugate() * Wind(time_s_);
}

void Airship::Loads(double t_s, const AirshipState& s, const AirshipControls& c,
                    Eigen::Vector3d* force, Eigen::Vector3d* moment) const {
  const AirshipConfig& k = config_;
  const Eigen::Quaterniond to_body = s.attitude.conjugate();
  Eigen::Vector3d f = to_body * Eigen::Vector3d(0.0, 0.0, mass_.buoyancy - mass_.weight);
  // Buoyancy acts at the centre of buoyancy, above the centre of gravity.
  const Eigen::Vector3d centre_of_buoyancy(0.0, 0.0, k.cg_below_cb);
  Eigen::Vector3d m = centre_of_buoyancy.cross(to_body * Eigen::Vector3d(0.0, 0.0, mass_.buoyancy));

  if (k.aerodynamics) {
    const Eigen::Vector3d air = s.velocity - to_body * Wind(t_s);
    const double half_rho = 0.5 * k.air_density;
    const double a = k.length / 2.0;
    // Hull: axial drag on V^(2/3), cross-flow drag on the side area, and the
    // cross-flow drag of the hull turning about its centre (∫ x·x|x| dx = a⁴/2).
    f.x() -=
        half_rho * k.axial_drag_coefficient * std::pow(k.volume, 2.0 / 3.0) * SignedSquare(air.x());
    const double side_area = M_PI / 4.0 * k.length * k.diameter;
    f.y() -= half_rho * k.crossflow_drag_coefficient * side_area * SignedSquare(air.y());
    f.z() -= half_rho * k.crossflow_drag_coefficient * side_area * SignedSquare(air.z());
    const double turning =
        half_rho * k.crossflow_drag_coefficient * k.diameter * std::pow(a, 4) / 2.0;
    m.y() -= turning * SignedSquare(s.rates.y());
    m.z() -= turning * SignedSquare(s.rates.z());

    // Fins: lift ~ V·(normal velocity) at the tail, plus the surfaces' share
    // ~ u|u|·deflection; both pairs have twice one fin's area.
    const Eigen::Vector3d tail(-k.fin_arm, 0.0, 0.0);
    const Eigen::Vector3d at_tail = air + s.rates.cross(tail);
    const double speed = at_tail.norm();
    const double v4 = std::pow(speed, 4), on4 = std::pow(k.fin_onset_speed, 4);
    const double onset = v4 / (v4 + on4);
    const double fin = half_rho * k.fin_area * k.fin_lift_slope * onset;
    const double max_surface = k.max_surface_deg * M_PI / 180.0;
    const double deflect = k.control_effectiveness * SignedSquare(at_tail.x());
    const Eigen::Vector3d fins(
        0.0, -2.0 * fin * (speed * at_tail.y() + deflect * c.rudder * max_surface),
        -2.0 * fin * (speed * at_tail.z() + deflect * c.elevator * max_surface));
    f += fins;
    m += tail.cross(fins);
    // Rolling moves each fin's centre of pressure (at half a metre beyond the
    // hull) across the flow: roll damping, with the same onset.
    const double span = k.diameter / 2.0 + 0.5;
    m.x() -= 4.0 * fin * speed * span * span * s.rates.x();
  }

  // Main propellers on the tilting helix plane, and the tail rotor.
  const Eigen::Vector3d thrust =
      s.thrust * Eigen::Vector3d(std::cos(s.helix_rad), 0.0, std::sin(s.helix_rad));
  f += thrust;
  m += Eigen::Vector3d(k.propeller_x, 0.0, k.propeller_z).cross(thrust);
  const Eigen::Vector3d tail_force(0.0, -s.tail, 0.0);
  f += tail_force;
  m += Eigen::Vector3d(-k.tail_arm, 0.0, k.tail_z).cross(tail_force);
  *force = f;
  *moment = m;
}

Airship::Derivative Airship::Evaluate(double t_s, const AirshipState& s,
                                      const AirshipControls& c) const {
  Eigen::Vector3d force, moment;
  Loads(t_s, s, c, &force, &moment);
  if (contact_ != nullptr) {
    Eigen::Vector3d contact_force = Eigen::Vector3d::Zero(),
                    contact_moment = Eigen::Vector3d::Zero();
    contact_->Loads(s, &contact_force, &contact_moment);
    force += contact_force;
    moment += contact_moment;
  }
  const Eigen::Vector3d& M = mass_.inertia_mass;
  const Eigen::Vector3d& J = mass_.inertia_moment;
  const Eigen::Vector3d angular = J.cwiseProduct(s.rates);
  // The rigid body's momentum goes with the ground velocity, the added
  // mass's with the velocity through the air: in a steady wind the hull
  // feels only its motion through the air (Galilean invariance).
  const Eigen::Vector3d air = s.velocity - s.attitude.conjugate() * Wind(t_s);
  const Eigen::Vector3d added = (M - Eigen::Vector3d::Constant(mass_.mass)).cwiseProduct(air);
  const Eigen::Vector3d momentum = mass_.mass * s.velocity + added;
  Derivative d;
  // Kirchhoff's equations in the body frame: the -v × Mv term is the
  // Munk moment that turns a moving hull broadside.
  d.velocity_dot = (force - s.rates.cross(momentum)).cwiseQuotient(M);
  d.rates_dot = (moment - s.rates.cross(angular) - air.cross(added)).cwiseQuotient(J);
  d.position_dot = s.attitude * s.velocity;
  const Eigen::Quaterniond spin =
      s.attitude * Eigen::Quaterniond(0.0, s.rates.x(), s.rates.y(), s.rates.z());
  d.attitude_dot = 0.5 * spin.coeffs();
  const AirshipConfig& k = config_;
  d.thrust_dot = (std::clamp(c.power, 0.0, 1.0) * k.max_thrust - s.thrust) / k.thrust_time_constant;
  d.tail_dot =
      (std::clamp(c.tail_rotor, -1.0, 1.0) * k.tail_thrust - s.tail) / k.tail_time_constant;
  const double helix_target = std::clamp(c.helix, -1.0, 1.0) * k.max_helix_deg * M_PI / 180.0;
  const double rate = k.helix_rate_deg_s * M_PI / 180.0;
  d.helix_dot = std::clamp((helix_target - s.helix_rad) / kServoTimeConstant, -rate, rate);
  return d;
}

AirshipState Airship::Apply(const AirshipState& s, const Derivative& d, double h) {
  AirshipState out = s;
  out.position += h * d.position_dot;
  out.velocity += h * d.velocity_dot;
  out.rates += h * d.rates_dot;
  out.attitude.coeffs() += h * d.attitude_dot;
  out.attitude.normalize();
  out.thrust += h * d.thrust_dot;
  out.helix_rad += h * d.helix_dot;
  out.tail += h * d.tail_dot;
  return out;
}

void Airship::Step(double h, const AirshipControls& c) {
  const double t = time_s_;
  switch (config_.integrator) {
    case AirshipIntegrator::kSemiImplicitEuler: {
      // Velocities first, then the pose with the new velocities (symplectic
      // Euler); the attitude turns by the exact rotation of the new rates.
      const Derivative d = Evaluate(t, state_, c);
      state_.velocity += h * d.velocity_dot;
      state_.rates += h * d.rates_dot;
      state_.thrust += h * d.thrust_dot;
      state_.helix_rad += h * d.helix_dot;
      state_.tail += h * d.tail_dot;
      state_.position += h * (state_.attitude * state_.velocity);
      state_.attitude = (state_.attitude * Exp(h * state_.rates)).normalized();
      break;
    }
    case AirshipIntegrator::kMidpoint: {
      const Derivative d1 = Evaluate(t, state_, c);
      const Derivative d2 = Evaluate(t + h / 2, Apply(state_, d1, h / 2), c);
      state_ = Apply(state_, d2, h);
      break;
    }
    case AirshipIntegrator::kRk4: {
      const Derivative d1 = Evaluate(t, state_, c);
      const Derivative d2 = Evaluate(t + h / 2, Apply(state_, d1, h / 2), c);
      const Derivative d3 = Evaluate(t + h / 2, Apply(state_, d2, h / 2), c);
      const Derivative d4 = Evaluate(t + h, Apply(state_, d3, h), c);
      Derivative sum;
      sum.position_dot =
          (d1.position_dot + 2 * d2.position_dot + 2 * d3.position_dot + d4.position_dot) / 6;
      sum.velocity_dot =
          (d1.velocity_dot + 2 * d2.velocity_dot + 2 * d3.velocity_dot + d4.velocity_dot) / 6;
      sum.rates_dot = (d1.rates_dot + 2 * d2.rates_dot + 2 * d3.rates_dot + d4.rates_dot) / 6;
      sum.attitude_dot =
          (d1.attitude_dot + 2 * d2.attitude_dot + 2 * d3.attitude_dot + d4.attitude_dot) / 6;
      sum.thrust_dot = (d1.thrust_dot + 2 * d2.thrust_dot + 2 * d3.thrust_dot + d4.thrust_dot) / 6;
      sum.helix_dot = (d1.helix_dot + 2 * d2.helix_dot + 2 * d3.helix_dot + d4.helix_dot) / 6;
      sum.tail_dot = (d1.tail_dot + 2 * d2.tail_dot + 2 * d3.tail_dot + d4.tail_dot) / 6;
      state_ = Apply(state_, sum, h);
      break;
    }
  }
  time_s_ = t + h;
}

void Airship::Advance(double dt, const AirshipControls& controls) {
  if (!(dt > 0.0)) return;
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / config_.step_s - 1e-9)));
  const double h = dt / steps;
  for (int i = 0; i < steps; ++i) Step(h, controls);
}

double Airship::Energy() const {
  const AirshipState& s = state_;
  const double kinetic = 0.5 * s.velocity.dot(mass_.inertia_mass.cwiseProduct(s.velocity)) +
                         0.5 * s.rates.dot(mass_.inertia_moment.cwiseProduct(s.rates));
  const double buoyancy_height =
      s.position.z() + (s.attitude * Eigen::Vector3d(0.0, 0.0, config_.cg_below_cb)).z();
  return kinetic + mass_.weight * s.position.z() - mass_.buoyancy * buoyancy_height;
}

Eigen::Vector3d Airship::YawPitchRoll() const {
  const Eigen::Matrix3d r = state_.attitude.toRotationMatrix();
  return {std::atan2(r(1, 0), r(0, 0)), std::asin(std::clamp(r(2, 0), -1.0, 1.0)),
          std::atan2(r(2, 1), r(2, 2))};
}

bool Airship::Finite() const {
  const AirshipState& s = state_;
  return s.position.allFinite() && s.velocity.allFinite() && s.rates.allFinite() &&
         s.attitude.coeffs().allFinite() && std::isfinite(s.thrust) && std::isfinite(s.helix_rad) &&
         std::isfinite(s.tail);
}

}  // namespace haptel::models
