#include "haptel/haptics/sim_device.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"

namespace haptel::haptics {

namespace {
/// Below this speed an axis may stick (Coulomb friction holds it).
constexpr double kStickSpeed = 1e-4;  // m/s

double Sign(double v) { return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0); }

/// Small deterministic noise for the glove (xorshift), allocation-free.
double Noise(uint64_t& state) {
  state ^= state << 13;
  state ^= state >> 7;
  state ^= state << 17;
  return static_cast<double>(state % 2001) / 1000.0 - 1.0;  // [-1, 1]
}
}  // namespace

SimDevice::SimDevice(const DeviceConfig& config, const OperatorConfig& muscle)
    : config_(Validated(config).sim), muscle_(Validated(muscle)) {
  description_.name = config.name;
  description_.has_side = config.sides;
  description_.wrist_force_limit = config.sim.force_limit;
  description_.finger_force_limit = config.safety.finger_force_limit;
  description_.has_glove = config.has_glove;
  description_.has_grasp = config.has_grasp;
  // Hidden truth: a few percent off the nominal values, reproducible per seed.
  std::mt19937 rng(static_cast<uint32_t>(config.sim.seed));
  std::uniform_real_distribution<double> percent(-0.05, 0.05);
  std::uniform_real_distribution<double> centimetres(-0.03, 0.03);
  std::uniform_real_distribution<double> gain(0.004, 0.008);  // rad per sensor count
  std::uniform_real_distribution<double> offset(-0.3, 0.1);   // rad
  // The tremor's own draws, so that the truth above is the same with or without it.
  std::mt19937 tremor_rng(static_cast<uint32_t>(config.sim.seed) ^ 0x7e3a2u);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  // The tremor: each axis a few percent off the nominal frequency, so the
  // hand traces no fixed figure. Its force is what moves the held arm by the
  // amplitude at that frequency: the arm's impedance there, |k − mω² + jcω|,
  // the muscle's spring k and the arm's mass m, c the muscle's and the
  // arm's damping plus Coulomb friction's describing function (4·F_c/(π·A·ω):
  // the damping that dissipates as much per cycle).
  std::uniform_real_distribution<double> spread(-0.06, 0.06);
  const double omega = 2.0 * std::numbers::pi * muscle_.tremor_frequency_hz;
  for (int i = 0; i < 3; ++i) tremor_omega_[i] = omega * (1.0 + spread(tremor_rng));
  if (muscle_.tremor_amplitude > 0.0) {
    const double a = muscle_.tremor_amplitude;
    const double c = muscle_.muscle_damping + config_.damping +
                     4.0 * config_.coulomb_friction / (std::numbers::pi * a * omega);
    tremor_force_ =
        a * std::hypot(muscle_.muscle_stiffness - config_.arm_mass * omega * omega, c * omega);
  }
  for (int s = 0; s < kSides; ++s) {
    orientation_[s].Store({1.0, 0.0, 0.0, 0.0});
    SimArmTruth& t = truth_[s];
    for (int i = 0; i < 3; ++i) {
      t.tracker_scale[i] = 0.01 * (1.0 + percent(rng));  // device reports ~cm
      t.tracker_offset[i] = centimetres(rng);
      t.force_slope[i] = 1.0 + 4.0 * percent(rng);  // ±20 %
    }
    t.finger_force_slope = 1.0 + 2.0 * percent(rng);
    for (int j = 0; j < kGloveJoints; ++j) {
      t.glove_gain[j] = gain(rng);
      t.glove_offset[j] = offset(rng);
    }
    arms_[s].tremor_phase = {phase(tremor_rng), phase(tremor_rng), phase(tremor_rng)};
    glove_noise_state_[s] =
        0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(s) + static_cast<uint64_t>(config.sim.seed);
    lost_[s].store(false);
  }
}

double SimDevice::UnbalancedMass(const Vec3d& p) const {
  // Normalised position in the workspace; the exoskeleton is least balanced
  // far forward and high up, with a sideways bump so the field is not linear.
  std::array<double, 3> u{};
  for (int i = 0; i < 3; ++i) {
    u[i] = std::clamp(
        (p[i] - config_.workspace_min[i]) / (config_.workspace_max[i] - config_.workspace_min[i]),
        0.0, 1.0);
  }
  const double shape =
      0.25 + 0.45 * u[0] * u[0] + 0.2 * u[2] + 0.1 * std::sin(std::numbers::pi * u[1]);
  return config_.exo_unbalanced_mass * shape;
}

void SimDevice::SetOperatorTarget(Side side, const Vec3d& target) {
  operator_[Index(side)].Store({target, true});
}

void SimDevice::Release(Side side) {
  OperatorInput in = operator_[Index(side)].Load();
  in.holding = false;
  operator_[Index(side)].Store(in);
  arms_[Index(side)].integral = Vec3d{};
}

void SimDevice::SetGlovePosture(Side side, const std::array<double, kGloveJoints>& angles) {
  posture_[Index(side)].Store(angles);
}

void SimDevice::SetWristOrientation(Side side, const std::array<double, 4>& orientation) {
  orientation_[Index(side)].Store(orientation);
}

void SimDevice::Place(Side side, const Vec3d& position) {
  Arm& arm = arms_[Index(side)];
  arm.position = position;
  arm.velocity = Vec3d{};
  arm.integral = Vec3d{};
  // Start the integral at what holds the arm against its weight.
  arm.integral[2] = std::clamp(UnbalancedMass(position) * kGravity, -0.6 * muscle_.muscle_max_force,
                               0.6 * muscle_.muscle_max_force);
  operator_[Index(side)].Store({position, true});
}

void SimDevice::Step(Arm& arm, const OperatorInput& input, double dt) {
  const double max_integral = 0.6 * muscle_.muscle_max_force;
  const double weight = UnbalancedMass(arm.position) * kGravity;
  for (int i = 0; i < 3; ++i) {
    double muscle = 0.0;
    if (input.holding) {
      const double error = input.target[i] - arm.position[i];
      arm.integral[i] = std::clamp(arm.integral[i] + muscle_.muscle_integral_gain * error * dt,
                                   -max_integral, max_integral);
      muscle = std::clamp(muscle_.muscle_stiffness * error + arm.integral[i] -
                              muscle_.muscle_damping * arm.velocity[i],
                          -muscle_.muscle_max_force, muscle_.muscle_max_force);
      if (tremor_force_ > 0.0) {
        arm.tremor_phase[i] =
            std::fmod(arm.tremor_phase[i] + tremor_omega_[i] * dt, 2.0 * std::numbers::pi);
        muscle += tremor_force_ * std::sin(arm.tremor_phase[i]);
      }
    }
    const double gravity = i == 2 ? -weight : 0.0;
    const double drive = muscle + arm.device_force[i] + gravity - config_.damping * arm.velocity[i];
    double& v = arm.velocity[i];
    if (std::abs(v) < kStickSpeed && std::abs(drive) <= config_.coulomb_friction) {
      v = 0.0;  // static friction holds
      continue;
    }
    const double friction = -config_.coulomb_friction * Sign(std::abs(v) < kStickSpeed ? drive : v);
    const double before = v;
    v += (drive + friction) / config_.arm_mass * dt;
    if (before != 0.0 && Sign(before) != Sign(v) && std::abs(drive) <= config_.coulomb_friction)
      v = 0.0;
    double& x = arm.position[i];
    x += v * dt;
    if (x < config_.workspace_min[i]) {
      x = config_.workspace_min[i];
      v = std::max(0.0, v);
    } else if (x > config_.workspace_max[i]) {
      x = config_.workspace_max[i];
      v = std::min(0.0, v);
    }
  }
}

DeviceStatus SimDevice::ReadWrist(Side side, int64_t now_ns, WristRaw& out) {
  const int s = Index(side);
  if (lost_[s].load(std::memory_order_relaxed)) return DeviceStatus::kLost;
  Arm& arm = arms_[s];
  if (arm.last_ns != 0) {
    // Sub-steps of at most 1 ms keep the integration stable after a late tick.
    double remaining = std::min(0.05, static_cast<double>(now_ns - arm.last_ns) * 1e-9);
    const OperatorInput input = operator_[s].Load();
    while (remaining > 1e-9) {
      const double dt = std::min(remaining, 1e-3);
      Step(arm, input, dt);
      remaining -= dt;
    }
  }
  arm.last_ns = now_ns;
  const SimArmTruth& t = truth_[s];
  out.t_ns = now_ns;
  for (int i = 0; i < 3; ++i) {
    const double res = config_.encoder_resolution;
    const double measured = res > 0 ? std::round(arm.position[i] / res) * res : arm.position[i];
    out.position[i] = (measured - t.tracker_offset[i]) / t.tracker_scale[i];
  }
  out.orientation = orientation_[s].Load();
  return DeviceStatus::kOk;
}

DeviceStatus SimDevice::ReadGlove(Side side, int64_t now_ns, GloveRaw& out) {
  const int s = Index(side);
  if (lost_[s].load(std::memory_order_relaxed)) return DeviceStatus::kLost;
  const SimArmTruth& t = truth_[s];
  const std::array<double, kGloveJoints> angles = posture_[s].Load();
  out.t_ns = now_ns;
  for (int j = 0; j < kGloveJoints; ++j) {
    const double noise =
        config_.glove_noise > 0 ? config_.glove_noise * Noise(glove_noise_state_[s]) : 0.0;
    out.sensors[j] =
        std::round((angles[j] - t.glove_offset[j]) / t.glove_gain[j] + noise);  // integer counts
  }
  for (int f = 0; f < kFingers; ++f) out.grasp[f] = arms_[s].finger_force[f] / t.finger_force_slope;
  return DeviceStatus::kOk;
}

Vec3d SimDevice::MeasureForce(Side side, const Vec3d& command) const {
  const SimArmTruth& t = truth_[Index(side)];
  Vec3d f{t.force_slope[0] * command[0], t.force_slope[1] * command[1],
          t.force_slope[2] * command[2]};
  LimitForce(f, config_.force_limit);  // the hardware saturates, whatever it is told
  return f;
}

DeviceStatus SimDevice::WriteWristForce(Side side, const Vec3d& command) {
  const int s = Index(side);
  if (lost_[s].load(std::memory_order_relaxed)) return DeviceStatus::kLost;
  arms_[s].device_force = MeasureForce(side, command);
  return DeviceStatus::kOk;
}

DeviceStatus SimDevice::WriteFingerForces(Side side, const std::array<double, kFingers>& command) {
  const int s = Index(side);
  if (lost_[s].load(std::memory_order_relaxed)) return DeviceStatus::kLost;
  const double slope = truth_[s].finger_force_slope;
  for (int f = 0; f < kFingers; ++f) {
    arms_[s].finger_force[f] = std::clamp(slope * command[f], 0.0, description_.finger_force_limit);
  }
  return DeviceStatus::kOk;
}

}  // namespace haptel::haptics
