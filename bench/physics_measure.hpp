#pragma once
/// @file The measurements behind `haptel bench physics` (physics_bench.hpp),
/// compiled twice: into haptel_bench against double-precision Bullet, and into
/// haptel-physics-bench-float against float Bullet. Only PhysicsWorld's own
/// API is used here (no Bullet header), so the code is the same for both.
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptel/config/physics.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::bench::wp {

using Vec3d = haptics::Vec3d;

/// The grid of the work-precision diagram.
inline const std::vector<double> kStepsMs{0.25, 0.5, 1.0, 2.0, 4.0, 8.0};
inline const std::vector<int> kIterations{5, 10, 20};
/// Reference: one run at a tenth of the finest step, with twice the largest
/// iteration count; every grid step is a multiple of the trajectory's sample.
constexpr double kReferenceStepMs = 0.025;
constexpr int kReferenceIterations = 40;
constexpr double kTrajectoryDtS = 0.00025;  ///< recorded at 4 kHz
constexpr double kTrajectoryS = 2.0;
constexpr double kPeakSpeed = 0.3;     ///< m/s
constexpr double kPushS = 1.0;         ///< the push into the table, touch-down included
constexpr double kGraspSettleS = 0.3;  ///< the grasp: the palms close on the box,
constexpr double kGraspLiftS = 1.0;    ///< lift it 10 cm,
constexpr double kGraspHoldS = 5.0;    ///< and hold it

/// What a run measures: the grid and the scenarios' lengths. The full run's
/// is the constants above; a smoke run's (`--smoke`) a corner of the grid
/// with the default in it, and shorter scenarios, the reference step and
/// iterations unchanged.
struct Plan {
  std::vector<double> steps_ms = kStepsMs;
  std::vector<int> iterations = kIterations;
  double trajectory_s = kTrajectoryS;
  double push_s = kPushS;
  double grasp_hold_s = kGraspHoldS;
  double grasp_s() const { return kGraspSettleS + kGraspLiftS + grasp_hold_s; }
};
Plan FullPlan();
Plan SmokePlan();

/// A recorded wrist trajectory: pose samples every dt.
struct Trajectory {
  double dt = kTrajectoryDtS;
  std::vector<Vec3d> position;
  std::vector<std::array<double, 4>> orientation;
  double duration() const { return dt * static_cast<double>(position.size() - 1); }
  /// Linear (position) and normalised-linear (orientation) interpolation.
  haptics::HandSample At(double t) const;
};

/// A deterministic human-like reach of `seconds`: sums of sines (0.3–1.7 Hz)
/// per axis, eased in over 0.5 s, scaled to a peak speed of 0.3 m/s, with the
/// wrist turning ±0.3 rad about z.
Trajectory MakeTrajectory(double seconds = kTrajectoryS);
void SaveTrajectory(const std::filesystem::path& file, const Trajectory& trajectory);
/// nullopt when the file is missing or not a trajectory of this bench `seconds` long.
std::optional<Trajectory> LoadTrajectory(const std::filesystem::path& file,
                                         double seconds = kTrajectoryS);

/// Proxy wrist positions along `trajectory` at every sample time (index i ↔
/// t = i·dt; index 0 is the placement), simulated at `step_s`, `iterations`.
std::vector<Vec3d> TrackRun(const PhysicsConfig& base, const Trajectory& trajectory, double step_s,
                            int iterations, double* cpu_s = nullptr, long* resets = nullptr);
/// The ground truth: TrackRun at kReferenceStepMs and kReferenceIterations,
/// its config marked a reference run (PhysicsConfig::reference: a step finer
/// than a physics thread may ask for, on a world stepped here, never a thread).
std::vector<Vec3d> ReferenceRun(const PhysicsConfig& base, const Trajectory& trajectory);
void SaveReference(const std::filesystem::path& file, const std::vector<Vec3d>& reference);
std::optional<std::vector<Vec3d>> LoadReference(const std::filesystem::path& file);

struct Point {
  double step_ms = 0.0;
  int iterations = 0;
  std::string precision;
  double cpu_per_sim_s = 0.0;    ///< thread CPU s per simulated s, all three scenarios
  double tracking_err_mm = 0.0;  ///< RMS |proxy − reference proxy| along the trajectory
  double penetration_mm = 0.0;   ///< deepest over a 10 N push, touch-down at 0.1 m/s included
  double slip_mm = 0.0;          ///< box displacement relative to the palms over a 5 s hold
  // CSV only:
  double lag_mm = 0.0;  ///< RMS |proxy − tracked wrist|
  double penetration_rest_mm =
      0.0;          ///< mean over the push's last 0.2 s (negative: above the surface)
  long resets = 0;  ///< NaN/Inf resets of hands and bodies
};

/// One point of the grid; the push and the grasp's hold last as long as `plan` says.
Point Measure(const PhysicsConfig& base, const Trajectory& trajectory,
              const std::vector<Vec3d>& reference, double step_ms, int iterations,
              const std::string& precision, const Plan& plan = {});

/// {"step_ms":…,"iterations":…,"precision":"…",…} with the JSON fields, plus
/// the CSV-only ones when `extra`.
std::string ToJson(const Point& p, bool extra);
/// Every point ToJson(…, true) wrote in `text`.
std::vector<Point> ParsePoints(const std::string& text);

}  // namespace haptel::bench::wp
