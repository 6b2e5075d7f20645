#pragma once
/// @file A simulated two-arm haptic device with a simulated operator's arm.
///
/// Each arm is a point mass moved by the operator's muscle force plus the
/// device force, with viscous friction. The "muscle" is a spring-damper with
/// a slow integral term toward a target the operator sets — a person who
/// pushes harder when something pulls back, but cannot push through a stiff
/// wall. Integration happens in Read, on the servo thread, at the servo rate.
#include <array>

#include "haptel/config/run.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

class SimDevice final : public Device {
 public:
  SimDevice(const SimDeviceConfig& device, const OperatorConfig& muscle);

  bool HasSide(Side) const override { return true; }
  DeviceStatus Read(Side side, int64_t now_ns, HandSample& out) override;
  DeviceStatus WriteForce(Side side, const Vec3d& force) override;
  double wrist_force_limit() const override { return device_.force_limit; }

  /// Operator thread: where the simulated person wants the hand to be.
  void SetOperatorTarget(Side side, const Vec3d& target);
  /// Test hook: puts the arm at rest at `position`.
  void Place(Side side, const Vec3d& position);

 private:
  struct Arm {
    Vec3d position{};
    Vec3d velocity{};
    Vec3d device_force{};
    Vec3d integral{};  ///< integral part of the muscle force, N
    int64_t last_ns = 0;
  };
  void Integrate(Arm& arm, const Vec3d& target, double dt);

  SimDeviceConfig device_;
  OperatorConfig muscle_;
  std::array<Arm, kSides> arms_{};
  std::array<Seqlock<Vec3d>, kSides> targets_;
};

}  // namespace haptel::haptics
