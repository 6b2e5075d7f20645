#include "haptel/haptics/servo_loop.hpp"

#include <cmath>

#include "haptel/haptics/force_field.hpp"

namespace haptel::haptics {

ServoLoop::ServoLoop(Device& device, Hal& hal, const ServoConfig& config)
    : device_(device),
      hal_(hal),
      thread_({.name = "haptel-servo",
               .rate_hz = config.rate_hz,
               .realtime_priority = config.realtime_priority,
               .max_catch_up_periods = 10},
              [this](int64_t now_ns) { Tick(now_ns); }) {}

ServoLoop::~ServoLoop() { Stop(); }

void ServoLoop::Start() { thread_.Start(); }
void ServoLoop::Stop() { thread_.Stop(); }

void ServoLoop::Tick(int64_t now_ns) {
  for (int i = 0; i < kSides; ++i) {
    const auto side = static_cast<Side>(i);
    if (!device_.HasSide(side)) continue;
    const DeviceStatus status = device_.Read(side, now_ns, sample_);
    if (status == DeviceStatus::kLost) {
      device_lost_ticks_.fetch_add(1, std::memory_order_relaxed);
      sample_.valid = false;
      hal_.PublishSample(side, sample_);
      last_force_[i] = Vec3d{};
      device_.WriteForce(side, Vec3d{});
      continue;
    }
    Vec3d force{};
    if (status == DeviceStatus::kOk) {
      const ForceField field = hal_.Field(side);
      force = EvaluateForceField(field, sample_.position, sample_.velocity);
      const bool finite = std::isfinite(force[0]) && std::isfinite(force[1]) && std::isfinite(force[2]);
      if (!finite) non_finite_forces_.fetch_add(1, std::memory_order_relaxed);
      if (LimitForce(force, device_.wrist_force_limit()) && finite) {
        forces_limited_.fetch_add(1, std::memory_order_relaxed);
      }
      sample_.force = force;
      hal_.PublishSample(side, sample_);
      last_force_[i] = force;
    } else {
      force = last_force_[i];  // no new reading: hold the last force
    }
    device_.WriteForce(side, force);
  }
}

ServoCounters ServoLoop::Counters() const {
  return {device_lost_ticks_.load(), forces_limited_.load(), non_finite_forces_.load()};
}

}  // namespace haptel::haptics
