#pragma once
/// @file Per-user, per-device calibration: what turns device units into SI.
///
/// Written by `haptel calibrate`, validated by LoadCalibration, applied by the
/// servo loop (wrist) and the HAL's accessors (glove).
#include <array>
#include <filesystem>
#include <string>

#include "haptel/config/archive.hpp"

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

  /// The ranges are plausibility only: they catch garbage (a unit mix-up by
  /// orders of magnitude); the fit itself decides the values.
  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Comment, config::EachElement, config::NonZero, config::Range, config::Required;
    a->Visit(HAPTEL_NVP(tracker_scale), Required{}, NonZero{}, EachElement{}, Range{-1e3, 1e3},
             Comment{"m per device unit"});
    a->Visit(HAPTEL_NVP(tracker_offset), Required{}, EachElement{}, Range{-1e3, 1e3}, Comment{"m"});
    a->Visit(HAPTEL_NVP(glove_gain), Required{}, NonZero{}, EachElement{}, Range{-1e3, 1e3},
             Comment{"rad per count"});
    a->Visit(HAPTEL_NVP(glove_offset), Required{}, EachElement{}, Range{-1e3, 1e3}, Comment{"rad"});
    a->Visit(HAPTEL_NVP(force_slope), Required{}, NonZero{}, EachElement{}, Range{-1e4, 1e4},
             Comment{"N per device unit"});
    a->Visit(HAPTEL_NVP(force_residual), Required{}, Range{0.0, 1e4}, Comment{"N (RMS)"});
    a->Visit(HAPTEL_NVP(finger_force_slope), Required{}, Comment{"N per device unit"});
  }

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

  /// Every field but `file`.
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(device), config::Required{});
    a->Visit(HAPTEL_NVP(user), config::Required{});
    a->Group(
        "arms",
        [this](auto* side) {
          side->Visit(config::MakeNameValue("left", &arms[0]),
                      config::Required{"the left arm's calibration (a mapping of keys)"});
          side->Visit(config::MakeNameValue("right", &arms[1]),
                      config::Required{"the right arm's calibration (a mapping of keys)"});
        },
        config::Required{"a mapping with the 'left' and 'right' arms"});
  }

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
