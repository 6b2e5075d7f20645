#pragma once
/// @file `haptel calibrate`: the calibration procedure on a device, attended
/// (prompts, Enter, typed gauge readings) or, on the sim device, unattended.
///
/// Steps, on every side the device has:
/// 1. Glove (if the device has one): the four postures of GlovePostures(),
///    each captured as the mean of a few readings; the operator may redo any
///    posture; GloveCalibrator fits every sensor.
/// 2. Tracker: the wrist is put in a jig at each reference position (true
///    metres in the device frame both arms share) and read once still;
///    FitTracker fits scale and offset per axis.
/// 3. Force: a set of single-axis commands up to `force_fraction` of the
///    wrist force limit; a force gauge on the wrist reads each; FitForce.
/// The finger force slope is not measured (no finger gauge yet): it is kept
/// from `options.base`.
///
/// Unattended (`auto_mode`, sim device only) the simulated operator does the
/// work: postures via SetGlovePosture (in a shuffled order, the first one
/// fumbled half-formed and redone at the end, so the redo path always runs),
/// the wrist moved to each reference with SetOperatorTarget, docked in the
/// "jig" with Place once it has settled, and the gauge is MeasureForce.
/// Simulated time advances 1 ms per wrist read; nothing sleeps.
///
/// Tolerances against the sim's hidden truth (worst cases from the physics
/// of the measurement, asserted per sensor/axis by the tests):
/// - Tracker: readings are exact but for encoder quantisation r (60 µm, so
///   ≤ r/2 per reading); with references at ±a about the centre c on each
///   axis the least-squares errors are |Δscale/scale| ≤ r/(2a) = 0.024 %
///   (a = 0.125 m) and |Δoffset| ≤ r/2 + r/(2a)·|c − offset| ≤ 0.06 mm.
/// - Glove: counts are rounded (≤ 0.5 count each). With N = Δθ/gain counts
///   between the two postures used: |Δgain/gain| ≤ 1/(N − 1): ≤ 0.8 % for
///   flexions (Δθ ≥ 1.1 rad), ≤ 2.8 % for the finger abductions (Δθ = 0.3
///   rad) at the sim's coarsest 0.008 rad/count; angles over the postures'
///   range within half a count (≤ 0.004 rad); the offset, an extrapolation to
///   0 counts, within gain·(|raw_a| + |raw_b|) / (2·|raw_b − raw_a|)
///   (≤ 0.013 rad for the sim's offsets in [−0.3, 0.1] rad).
/// - Force: the sim's gauge is exact, so slopes are recovered to rounding
///   (relative 1e-9) with a residual below 1e-9 N; on hardware the residual
///   reports the gauge's own noise.
#include <iosfwd>
#include <string>
#include <vector>

#include "haptel/calibration/calibration.hpp"
#include "haptel/config/calibration.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

class SimDevice;
struct SimArmTruth;

/// Centre and half-span (m) of the default tracker reference poses.
inline constexpr Vec3d kReferenceCentre{0.05, 0.0, 0.02};
constexpr double kReferenceHalfSpan = 0.125;

/// The default reference poses: the centre and ±kReferenceHalfSpan along each
/// axis (7 poses), inside the sim's workspace and where its operator can
/// hold the arm against the exoskeleton's weight.
std::vector<Vec3d> DefaultTrackerReferences();

struct CalibrationOptions {
  bool auto_mode = false;        ///< unattended, sim device only
  std::string user = "default";  ///< recorded in the file
  bool glove = true;             ///< steps to run; skipped ones keep `base`
  bool tracker = true;
  bool force = true;
  DeviceCalibration base;  ///< starting values (and the sides not present)
  std::vector<Vec3d> references = DefaultTrackerReferences();  ///< m, device frame
  double force_fraction = 0.7;  ///< largest command, × wrist force limit (slopes ≈ 1 ± 20 %)
  int glove_samples = 20;       ///< readings averaged per posture
  int wrist_samples = 50;       ///< readings averaged per reference pose
  unsigned seed = 1;            ///< shuffles the posture order in auto mode
};

/// Runs the steps on every side of `device`, prompting on `log` and reading
/// the operator's answers from `in` when not in auto mode. Throws
/// CalibrationError when a measurement is unusable or the device is lost.
DeviceCalibration RunCalibration(Device& device, const CalibrationOptions& options,
                                 std::ostream& log, std::istream& in);
/// Same, answers read from std::cin.
DeviceCalibration RunCalibration(Device& device, const CalibrationOptions& options,
                                 std::ostream& log);

/// Worst errors of one arm's calibration against the simulated truth.
struct TruthErrors {
  double tracker_scale_rel = 0.0;  ///< max over axes of |Δscale/scale|
  double tracker_offset_m = 0.0;   ///< max over axes of |Δoffset|, m
  double glove_gain_rel = 0.0;     ///< max over sensors of |Δgain/gain|
  double glove_offset_rad = 0.0;   ///< max over sensors of |Δoffset|, rad
  /// max over sensors of the angle error over the postures' range, rad
  double glove_angle_rad = 0.0;
  double force_slope_rel = 0.0;  ///< max over axes of |Δslope/slope|
};
TruthErrors CompareWithTruth(const ArmCalibration& calibration, const SimArmTruth& truth);

/// A readable table of the calibration per arm; with a sim device, the
/// errors against its truth too.
void PrintCalibrationSummary(std::ostream& out, const DeviceCalibration& calibration,
                             const Device& device);

/// `haptel calibrate [--device FILE] [--out FILE] [--auto] [--user NAME]`.
/// argv as main() received it; a leading "calibrate" word is accepted.
/// Returns 0 on success, 2 on bad arguments or configuration (one line on
/// stderr), 1 when the calibration itself fails.
int CalibrateMain(int argc, const char* const* argv);

}  // namespace haptel::haptics
