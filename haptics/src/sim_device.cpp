#include "haptel/haptics/sim_device.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/haptics/force_field.hpp"

namespace haptel::haptics {

SimDevice::SimDevice(const SimDeviceConfig& device, const OperatorConfig& muscle)
    : device_(device), muscle_(muscle) {}

void SimDevice::SetOperatorTarget(Side side, const Vec3d& target) {
  targets_[Index(side)].Store(target);
}

void SimDevice::Place(Side side, const Vec3d& position) {
  Arm& arm = arms_[Index(side)];
  arm.position = position;
  arm.velocity = Vec3d{};
  arm.integral = Vec3d{};
  targets_[Index(side)].Store(position);
}

void SimDevice::Integrate(Arm& arm, const Vec3d& target, double dt) {
  const double max_integral = 0.6 * muscle_.muscle_max_force;
  for (int i = 0; i < 3; ++i) {
    const double error = target[i] - arm.position[i];
    arm.integral[i] = std::clamp(arm.integral[i] + muscle_.muscle_integral_gain * error * dt,
                                 -max_integral, max_integral);
    const double muscle = std::clamp(muscle_.muscle_stiffness * error + arm.integral[i] -
                                         muscle_.muscle_damping * arm.velocity[i],
                                     -muscle_.muscle_max_force, muscle_.muscle_max_force);
    const double total = muscle + arm.device_force[i] - device_.damping * arm.velocity[i];
    // Semi-implicit Euler: stable for the stiffnesses used at 1 kHz.
    arm.velocity[i] += total / device_.arm_mass * dt;
    arm.position[i] += arm.velocity[i] * dt;
  }
}

DeviceStatus SimDevice::Read(Side side, int64_t now_ns, HandSample& out) {
  Arm& arm = arms_[Index(side)];
  if (arm.last_ns != 0) {
    // Sub-steps of at most 1 ms keep the integration stable after a late tick.
    double remaining = std::min(0.05, static_cast<double>(now_ns - arm.last_ns) * 1e-9);
    const Vec3d target = targets_[Index(side)].Load();
    while (remaining > 1e-9) {
      const double dt = std::min(remaining, 1e-3);
      Integrate(arm, target, dt);
      remaining -= dt;
    }
  }
  arm.last_ns = now_ns;
  out.t_ns = now_ns;
  out.valid = true;
  out.position = arm.position;
  out.velocity = arm.velocity;
  out.force = arm.device_force;
  return DeviceStatus::kOk;
}

DeviceStatus SimDevice::WriteForce(Side side, const Vec3d& force) {
  Vec3d limited = force;
  LimitForce(limited, device_.force_limit);  // the hardware saturates, whatever it is told
  arms_[Index(side)].device_force = limited;
  return DeviceStatus::kOk;
}

}  // namespace haptel::haptics
