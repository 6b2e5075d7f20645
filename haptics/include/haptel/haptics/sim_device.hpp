#pragma once
/// @file The `sim` device: a simulated two-arm exoskeleton with data gloves
/// and grasp strings, moved by a simulated operator.
///
/// Each arm is a point mass (per-axis dynamics) moved by the operator's muscle
/// force, the device force and an unbalanced exoskeleton weight that varies
/// with position (`exo_unbalanced_mass` at the worst place), against viscous
/// and Coulomb friction, inside a workspace box with hard stops. It reports
/// in device units through hidden "true" calibration parameters derived from
/// `seed` — tracker scale and offset, glove gains and offsets, force slopes —
/// with encoder quantisation, so calibration and gravity compensation have
/// something real to recover. Friction acts per axis (a simplification).
///
/// The muscle is a spring-damper with a slow, bounded integral term toward a
/// target the operator sets: a person who pushes harder when something pulls
/// back, but cannot push through a stiff wall. A held arm also shakes with
/// the operator's physiological tremor (OperatorConfig::tremor_amplitude at
/// tremor_frequency_hz): a force oscillation sized so that the arm moves by
/// the amplitude. A released arm has no muscle, and no tremor.
#include <array>
#include <atomic>

#include "haptel/config/device.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

/// The parameters a perfect calibration would find for one simulated arm.
struct SimArmTruth {
  Vec3d tracker_scale{};  ///< metres = scale · raw + offset
  Vec3d tracker_offset{};
  std::array<double, kGloveJoints> glove_gain{};  ///< radians = gain · raw + offset
  std::array<double, kGloveJoints> glove_offset{};
  Vec3d force_slope{};  ///< newtons = slope · command
  double finger_force_slope = 1.0;
};

class SimDevice final : public Device {
 public:
  static constexpr double kGravity = 9.81;  ///< m/s²

  /// Validates `config` and `muscle` first (ValidateOrThrow: ConfigFieldError).
  SimDevice(const DeviceConfig& config, const OperatorConfig& muscle);

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override;
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override;
  DeviceStatus WriteWristForce(Side side, const Vec3d& command) override;
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>& command) override;

  // --- The simulated operator (any thread). ---
  /// Where the operator wants the wrist, true metres; the operator holds on.
  void SetOperatorTarget(Side side, const Vec3d& target);
  /// The operator lets go of the arm: no muscle force until the next target.
  void Release(Side side);
  /// The hand posture the operator makes, joint angles in radians.
  void SetGlovePosture(Side side, const std::array<double, kGloveJoints>& angles);
  /// How the operator turns the wrist, a unit quaternion (w, x, y, z). The
  /// device renders forces, not torques, so the tracker reports it as is.
  void SetWristOrientation(Side side, const std::array<double, 4>& orientation);

  // --- Set-up, tests and calibration procedures (not while a loop runs). ---
  /// Puts the arm at rest at `position` (true metres), the operator holding it there.
  void Place(Side side, const Vec3d& position);
  /// Makes the side answer kLost (a pulled cable) or recover.
  void SetLost(Side side, bool lost) { lost_[Index(side)].store(lost); }
  const SimArmTruth& truth(Side side) const { return truth_[Index(side)]; }
  /// True wrist position and velocity (metres, m/s) after the last read.
  Vec3d TruePosition(Side side) const { return arms_[Index(side)].position; }
  Vec3d TrueVelocity(Side side) const { return arms_[Index(side)].velocity; }
  /// Unbalanced exoskeleton mass at a position, kg (its weight pulls down).
  double UnbalancedMass(const Vec3d& position) const;
  /// What a force gauge on the wrist reads for a command: newtons actually applied.
  Vec3d MeasureForce(Side side, const Vec3d& command) const;
  const SimArmConfig& config() const { return config_; }

 private:
  struct Arm {
    Vec3d position{};
    Vec3d velocity{};
    Vec3d device_force{};  ///< N actually applied
    Vec3d integral{};      ///< integral part of the muscle force, N
    Vec3d tremor_phase{};  ///< rad, per axis
    std::array<double, kFingers> finger_force{};
    int64_t last_ns = 0;
  };
  struct OperatorInput {
    Vec3d target{};
    bool holding = false;
  };
  void Step(Arm& arm, const OperatorInput& input, double dt);

  SimArmConfig config_;
  OperatorConfig muscle_;
  /// The tremor's force amplitude (N) and angular frequency (rad/s) per axis.
  double tremor_force_ = 0.0;
  Vec3d tremor_omega_{};
  DeviceDescription description_;
  std::array<SimArmTruth, kSides> truth_{};
  std::array<Arm, kSides> arms_{};
  std::array<Seqlock<OperatorInput>, kSides> operator_;
  std::array<Seqlock<std::array<double, kGloveJoints>>, kSides> posture_;
  std::array<Seqlock<std::array<double, 4>>, kSides> orientation_;
  std::array<std::atomic<bool>, kSides> lost_{};
  std::array<uint64_t, kSides> glove_noise_state_{};
};

}  // namespace haptel::haptics
