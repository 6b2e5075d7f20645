#pragma once
/// @file Applying a device calibration (made by calibration/): device units to
/// SI and back. These run in the servo loop: inline, noexcept,
/// allocation-free.
#include <array>
#include <string>

#include "haptel/config/calibration.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// Tracker reading → metres in the device frame.
inline Vec3d TrackerToMetres(const ArmCalibration& c, const Vec3d& raw) noexcept {
  return {c.tracker_scale[0] * raw[0] + c.tracker_offset[0],
          c.tracker_scale[1] * raw[1] + c.tracker_offset[1],
          c.tracker_scale[2] * raw[2] + c.tracker_offset[2]};
}

/// Metres → the tracker reading that would give them (inverse of TrackerToMetres).
inline Vec3d MetresToTracker(const ArmCalibration& c, const Vec3d& metres) noexcept {
  return {(metres[0] - c.tracker_offset[0]) / c.tracker_scale[0],
          (metres[1] - c.tracker_offset[1]) / c.tracker_scale[1],
          (metres[2] - c.tracker_offset[2]) / c.tracker_scale[2]};
}

/// Wrist force in newtons → device command (slopes are non-zero by validation).
inline Vec3d NewtonsToCommand(const ArmCalibration& c, const Vec3d& newtons) noexcept {
  return {newtons[0] / c.force_slope[0], newtons[1] / c.force_slope[1],
          newtons[2] / c.force_slope[2]};
}

/// One glove sensor's counts → joint angle, rad. `sensor` in [0, kGloveJoints).
inline double GloveToRadians(const ArmCalibration& c, int sensor, double raw) noexcept {
  return c.glove_gain[static_cast<size_t>(sensor)] * raw +
         c.glove_offset[static_cast<size_t>(sensor)];
}

/// All glove sensors → joint angles, rad.
inline void GloveToRadians(const ArmCalibration& c, const std::array<double, kGloveJoints>& raw,
                           std::array<double, kGloveJoints>& radians) noexcept {
  for (int j = 0; j < kGloveJoints; ++j)
    radians[static_cast<size_t>(j)] = GloveToRadians(c, j, raw[static_cast<size_t>(j)]);
}

/// The calibration of a device that reports SI itself
/// (DeviceDescription::reports_si): metres, radians and newtons unchanged.
inline DeviceCalibration IdentityCalibration(const std::string& device) {
  DeviceCalibration c;
  c.device = device;
  for (ArmCalibration& arm : c.arms) {
    arm.tracker_scale = {1.0, 1.0, 1.0};
    arm.tracker_offset = {0.0, 0.0, 0.0};
    arm.glove_gain.fill(1.0);
    arm.glove_offset.fill(0.0);
    arm.force_slope = {1.0, 1.0, 1.0};
    arm.finger_force_slope = 1.0;
  }
  return c;
}

/// Finger force in newtons → device command.
inline double FingerNewtonsToCommand(const ArmCalibration& c, double newtons) noexcept {
  return newtons / c.finger_force_slope;
}

}  // namespace haptel::haptics
