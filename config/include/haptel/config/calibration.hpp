#pragma once
/// @file Per-user, per-device calibration: what turns device units into SI.
///
/// Written by `haptel calibrate`, validated by LoadCalibration, applied by the
/// servo loop (wrist) and the HAL's accessors (glove).
#include <array>
#include <filesystem>
#include <string>

namespace haptel {

constexpr int kCalibrationGloveSensors = 22;

struct ArmCalibration {
  /// Tracker: metres = scale · raw + offset, per axis.
  std::array<double, 3> tracker_scale{0.01, 0.01, 0.01};
  std::array<double, 3> tracker_offset{0.0, 0.0, 0.0};
  /// Glove: radians = gain · raw + offset, per sensor.
  std::array<double, kCalibrationGloveSensors> glove_gain{};
  std::array<double, kCalibrationGloveSensors> glove_offset{};
  /// Force: newtons = slope · command, per axis; residual = RMS of the fit, N.
  std::array<double, 3> force_slope{1.0, 1.0, 1.0};
  double force_residual = 0.0;
  /// Finger forces: newtons = slope · command.
  double finger_force_slope = 1.0;

  ArmCalibration() { glove_gain.fill(1.0); }
};

struct DeviceCalibration {
  std::filesystem::path file;
  std::string device;  ///< name of the device it was measured on
  std::string user = "default";
  std::array<ArmCalibration, 2> arms;  ///< [left, right]
};

/// Loads and validates a calibration file (strict: unknown keys, non-finite
/// or zero slopes/scales are errors naming file, key and line).
DeviceCalibration LoadCalibration(const std::filesystem::path& file);
/// Writes a calibration file (creating parent folders) that LoadCalibration reads back.
void SaveCalibration(const std::filesystem::path& file, const DeviceCalibration& calibration);

}  // namespace haptel
