#pragma once
/// @file Calibration maths: fitting device units to SI from measurements, and
/// applying the result (DESIGN.md, "Calibration").
///
/// - Glove: each sensor is linear, radians = gain · counts + offset. The
///   operator makes four postures whose joint angles are known (the table
///   kGlovePostures); per sensor the map is solved from the two captured
///   postures whose raw readings differ most (best leverage against the
///   integer-count quantisation and sensor noise).
/// - Tracker: per axis metres = scale · raw + offset, least squares over
///   reference poses whose true positions are known in the one device frame
///   shared by both arms, so the two arms' calibrated positions agree.
/// - Force: per axis newtons = slope · command, least squares through the
///   origin over (command, gauge reading) pairs, with the fit's residual.
///
/// Applying a calibration is the real-time core's (haptics/calibrated_units.hpp).
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "haptel/config/calibration.hpp"
#include "haptel/haptics/calibrated_units.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

static_assert(kGloveJoints == kCalibrationGloveSensors, "glove sensor counts must agree");

/// A measurement cannot be turned into a calibration (degenerate or missing
/// data). The message names the sensor, axis or posture at fault.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------- glove ----

/// The 22 glove sensors, in device order (CyberGlove-style layout): thumb
/// (roll across the palm, MCP, IP, abduction), four fingers × (MCP, PIP,
/// DIP), three abductions between neighbouring fingers, palm arch, wrist
/// pitch (flexion +), wrist yaw (radial deviation, toward the thumb, +).
inline constexpr std::array<std::string_view, kGloveJoints> kGloveSensorNames{
    "thumb_roll",
    "thumb_mcp",
    "thumb_ip",
    "thumb_abduction",
    "index_mcp",
    "index_pip",
    "index_dip",
    "middle_mcp",
    "middle_pip",
    "middle_dip",
    "ring_mcp",
    "ring_pip",
    "ring_dip",
    "pinky_mcp",
    "pinky_pip",
    "pinky_dip",
    "index_middle_abduction",
    "middle_ring_abduction",
    "ring_pinky_abduction",
    "palm_arch",
    "wrist_pitch",
    "wrist_yaw"};

/// A calibration posture: the joint angles (rad) a hand makes when told `how`.
struct GlovePosture {
  std::string_view name;
  std::string_view how;  ///< instruction for the operator
  std::array<double, kGloveJoints> angles{};
};

constexpr int kGlovePostureCount = 4;

/// The four postures. Every sensor gets at least two postures whose angles
/// differ by ≥ 0.3 rad (finger abductions, the narrowest physical range),
/// ≥ 0.5 rad for most: flexions 1.1–1.6 rad (flat ↔ fist), thumb abduction
/// 1.0, wrist pitch 1.7 (spread ↔ bent), wrist yaw 0.7 (spread ↔ bent).
const std::array<GlovePosture, kGlovePostureCount>& GlovePostures();
/// Index of a posture by name, or -1.
int GlovePostureIndex(std::string_view name);

/// Two postures must differ by at least this much (rad) for a sensor to be
/// determined by them.
constexpr double kMinPostureAngleSpan = 0.25;

/// One sensor's fitted map and how it was obtained.
struct GloveSensorFit {
  double gain = 1.0;    ///< rad per count
  double offset = 0.0;  ///< rad
  int posture_a = -1;   ///< indices into GlovePostures() of the pair used
  int posture_b = -1;
  double raw_span = 0.0;  ///< |raw_b − raw_a|, counts
  /// Largest disagreement (rad) of the other captured postures with the fitted
  /// line: a consistency check on how well the operator made the postures.
  double check_error = 0.0;
};

struct GloveFit {
  std::array<GloveSensorFit, kGloveJoints> sensors{};
  /// Writes gains and offsets into `arm`.
  void ApplyTo(ArmCalibration& arm) const;
};

/// Collects the four postures in any order, then fits every sensor.
class GloveCalibrator {
 public:
  /// @param min_raw_span a sensor whose two best postures read closer than
  ///   this (counts) is degenerate: stuck, unplugged or not bent.
  explicit GloveCalibrator(double min_raw_span = 10.0) : min_raw_span_(min_raw_span) {}

  /// Records the raw sensors (e.g. the mean of a few readings) for a posture.
  /// Throws CalibrationError for an unknown posture name, a posture already
  /// captured (use Recapture) or a non-finite value.
  void Capture(std::string_view posture, const std::array<double, kGloveJoints>& raw);
  /// Replaces a posture already captured (the operator redoes it).
  void Recapture(std::string_view posture, const std::array<double, kGloveJoints>& raw);
  bool Captured(std::string_view posture) const;
  /// True when every sensor has two captured postures whose known angles
  /// differ by at least kMinPostureAngleSpan.
  bool Ready() const;
  /// The sensors not determined yet by the captured postures.
  std::vector<std::string_view> Undetermined() const;
  /// Fits every sensor; throws CalibrationError listing the sensors that are
  /// undetermined (not Ready) or degenerate (raw span below min_raw_span).
  GloveFit Fit() const;

 private:
  void Store(int index, const std::array<double, kGloveJoints>& raw);

  double min_raw_span_;
  std::array<std::optional<std::array<double, kGloveJoints>>, kGlovePostureCount> raw_{};
};

// -------------------------------------------------------------- tracker ----

/// Default tracker scale (device units are ~centimetres).
constexpr double kDefaultTrackerScale = 0.01;  // m per device unit
/// An axis's reference positions must span at least this much (m) for its
/// scale to be fitted; below it only the offset is fitted, with the default
/// scale (a scale from a short baseline would amplify reading errors).
constexpr double kMinTrackerScaleSpan = 0.05;  // m

struct TrackerReference {
  Vec3d raw{};     ///< tracker reading, device units
  Vec3d metres{};  ///< true position, m, in the device frame both arms share
};

struct TrackerFit {
  Vec3d scale{kDefaultTrackerScale, kDefaultTrackerScale, kDefaultTrackerScale};
  Vec3d offset{};
  std::array<bool, 3> scale_fitted{};  ///< false: default scale, offset only
  Vec3d residual_rms{};                ///< m, per axis
  void ApplyTo(ArmCalibration& arm) const;
};

/// Per axis, least squares metres = scale · raw + offset over the references.
/// An axis whose references span less than kMinTrackerScaleSpan (e.g. a single
/// reference pose) keeps `default_scale` and fits the offset only (mean of
/// metres − scale · raw). Throws CalibrationError with no reference, non-finite
/// input, or an axis whose raw readings do not change while the references do.
TrackerFit FitTracker(const std::vector<TrackerReference>& references,
                      double default_scale = kDefaultTrackerScale);

// ---------------------------------------------------------------- force ----

struct ForceSample {
  Vec3d command{};  ///< device units
  Vec3d newtons{};  ///< gauge reading
};

struct ForceFit {
  Vec3d slope{1, 1, 1};  ///< N per device unit
  /// Residual RMS per axis, N: sqrt(Σ(f − slope·c)² / (n − 1)) over all n
  /// samples (one parameter per axis), an estimate of the gauge noise.
  Vec3d residual_axis{};
  /// Over all axes: sqrt(ΣΣ(f − slope·c)² / (3n − 3)), N.
  double residual = 0.0;
  void ApplyTo(ArmCalibration& arm) const;
};

/// Per axis least squares through the origin. Throws CalibrationError for
/// non-finite input or an axis with fewer than two non-zero commands.
ForceFit FitForce(const std::vector<ForceSample>& samples);

}  // namespace haptel::haptics
