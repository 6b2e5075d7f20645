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

  /// Throws ConfigFieldError (naming the element: "glove_gain[3]") unless
  /// every value is finite and plausible, and scales, gains and slopes are
  /// non-zero (the finger slope > 0).
  void ValidateOrThrow() const;
};

struct DeviceCalibration {
  std::filesystem::path file;
  std::string device;  ///< name of the device it was measured on
  std::string user = "default";
  std::array<ArmCalibration, 2> arms;  ///< [left, right]

  /// Throws ConfigFieldError unless both arms are valid ("arms.left.*",
  /// "arms.right.*"). The names are not checked (a calibration made in code
  /// may have none; SaveCalibration requires them).
  void ValidateOrThrow() const;
};

/// Loads and validates (DeviceCalibration::ValidateOrThrow) a calibration file
/// (strict: unknown keys, non-finite or zero slopes/scales are errors naming
/// file, key and line).
DeviceCalibration LoadCalibration(const std::filesystem::path& file);
/// Writes a calibration file (creating parent folders) that LoadCalibration
/// reads back. ConfigError for a calibration without device and user names
/// or one DeviceCalibration::ValidateOrThrow refuses.
void SaveCalibration(const std::filesystem::path& file, const DeviceCalibration& calibration);

}  // namespace haptel
