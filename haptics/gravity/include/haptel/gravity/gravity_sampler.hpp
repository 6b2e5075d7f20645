#pragma once
/// @file Gravity compensation, offline: GravitySampler samples the grid of
/// vertical forces that hold the arm still (the online part, evaluated in
/// the servo loop, is haptics/gravity.hpp's GravityGrid). At each vertex it
/// lets go of the arm and holds it horizontally with a PD force while a
/// decision table nudges the vertical force until the arm holds still on
/// target (|z error| ≤ 1 mm, |vz| < 0.5 mm/s, continuously for 1 s). A
/// vertical damper (zero at rest, so it carries no weight) keeps the nudging
/// from swinging the arm. The result is a GravityGridData for SaveGravityGrid.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "haptel/config/calibration.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/gravity.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

// --------------------------------------------------------------- offline ---

/// Where the arm is relative to the vertex height, and how it moves.
enum class ZPosition : int { kAbove = 0, kAt = 1, kBelow = 2 };
enum class ZMotion : int { kUp = 0, kStill = 1, kDown = 2 };
enum class ForceStep : int { kLowerALot, kLowerALittle, kHold, kRaiseALittle, kRaiseALot };

/// The decision table, [position][motion]: how the vertical force changes at
/// each decision. Moving away from the target: a lot against the motion.
/// Stuck off target: a little towards it, until the force leaves the friction
/// band and the arm starts to move. Drifting back towards the target: leave
/// the force be (the sampler's damper keeps the return slow). Crossing the
/// target: a little against the motion, so friction stops the arm there. On
/// target and still: hold — the force holds the arm.
// clang-format off
inline constexpr std::array<std::array<ForceStep, 3>, 3> kGravityDecisionTable{{
    //             moving up                  still                      moving down
    /* above */ {{ForceStep::kLowerALot,    ForceStep::kLowerALittle, ForceStep::kHold}},
    /* at    */ {{ForceStep::kLowerALittle, ForceStep::kHold,         ForceStep::kRaiseALittle}},
    /* below */ {{ForceStep::kHold,         ForceStep::kRaiseALittle, ForceStep::kRaiseALot}},
}};
// clang-format on

constexpr ForceStep Decide(ZPosition position, ZMotion motion) {
  return kGravityDecisionTable[static_cast<int>(position)][static_cast<int>(motion)];
}
/// Signed force change, N (positive raises the force).
constexpr double StepNewtons(ForceStep step, double small_n, double large_n) {
  switch (step) {
    case ForceStep::kLowerALot:
      return -large_n;
    case ForceStep::kLowerALittle:
      return -small_n;
    case ForceStep::kHold:
      return 0.0;
    case ForceStep::kRaiseALittle:
      return small_n;
    case ForceStep::kRaiseALot:
      return large_n;
  }
  return 0.0;
}
/// |error| ≤ tolerance is "at"; error = z − target.
constexpr ZPosition ClassifyPosition(double error_m, double tolerance_m) {
  return error_m > tolerance_m ? ZPosition::kAbove
                               : (error_m < -tolerance_m ? ZPosition::kBelow : ZPosition::kAt);
}
/// |v| < tolerance is "still".
constexpr ZMotion ClassifyMotion(double vz_m_s, double tolerance_m_s) {
  return vz_m_s >= tolerance_m_s ? ZMotion::kUp
                                 : (vz_m_s <= -tolerance_m_s ? ZMotion::kDown : ZMotion::kStill);
}

struct GravitySamplerConfig {
  /// The box and its vertices (counts ≥ 2 per axis), m, calibrated device frame.
  std::array<double, 3> box_min{-0.15, -0.25, -0.15};
  std::array<double, 3> box_max{0.25, 0.25, 0.20};
  std::array<int, 3> counts{5, 5, 5};
  // Convergence: all three hold continuously for hold_s.
  double position_tolerance_m = 1e-3;
  double speed_tolerance_m_s = 0.5e-3;
  double hold_s = 1.0;
  /// Speed for the convergence test: displacement over this window / window
  /// (quantised trackers: a 60 µm step over 0.2 s reads 0.3 mm/s).
  double hold_speed_window_s = 0.2;
  /// A vertex that has not converged after this long fails the run.
  double vertex_timeout_s = 30.0;
  // Decision table: one decision per period; the motion state is the
  // displacement over the last period divided by the period. Defaults:
  // a little = 0.4 N/s, a lot = 5 N/s. With z_damping_n_s_m they converged
  // on the sim arm for friction 0.01–0.6 N, arm mass 0.4–4 kg and encoder
  // steps 10–200 µm (tests/haptics/test_gravity.cpp keeps a few of these).
  double decision_period_s = 0.05;
  double small_step_n = 0.02;  ///< "a little"
  double large_step_n = 0.25;  ///< "a lot"
  /// Below this speed the decision table calls the arm still (the
  /// convergence test uses speed_tolerance_m_s).
  double motion_still_m_s = 0.5e-3;
  /// Force at the first vertex; each later vertex starts from the force found
  /// at the one before (vertices are visited in a snake order, neighbours).
  double initial_force_n = 0.0;
  /// |vertical force| never exceeds this nor the device's wrist force limit.
  double max_force_n = 20.0;
  // Horizontal hold (PD on x and y, velocity as for the motion state).
  double xy_stiffness_n_m = 300.0;
  double xy_damping_n_s_m = 5.0;
  double xy_force_limit_n = 3.0;
  /// Vertical damping while refining, N·s/m (velocity as for the motion
  /// state). Without it the table's force, which integrates the motion, and
  /// the arm's mass make a lightly damped oscillator that can keep swinging.
  /// It holds no weight — it is zero at rest — so the sampled force is the
  /// table's alone (during the hold, |vz| < 0.5 mm/s: below 0.02 N).
  double z_damping_n_s_m = 40.0;
  std::string device;  ///< written into the grid data
};

struct GravityVertexReport {
  std::array<int, 3> index{};
  Vec3d target{};        ///< vertex, m
  double force_n = 0.0;  ///< sampled upward force
  double start_force_n = 0.0;
  double sim_time_s = 0.0;  ///< from release to convergence (includes the 1 s hold)
  int decisions = 0;        ///< force changes made (holds included)
  bool converged = false;
  double z_error_m = 0.0;  ///< at convergence or failure
  double speed_m_s = 0.0;  ///< hold-window speed at convergence or failure
};

struct GravitySampleReport {
  bool ok = false;
  std::string error;                          ///< why it failed ("" if ok)
  GravityGridData grid;                       ///< complete when ok
  std::vector<GravityVertexReport> vertices;  ///< in visiting order, up to the failure
  double sim_time_s = 0.0;                    ///< device time spent sampling
  double wall_time_s = 0.0;                   ///< filled by runners that measure it
  int64_t end_ns = 0;                         ///< device time of the last tick
};

/// The offline state machine. Drive it with Tick() at the servo rate (any
/// period; the simulated runner uses 1 ms). At each vertex it calls `place`
/// (which must bring the arm to the vertex at rest and let go of it), then
/// refines the vertical force until convergence or timeout.
class GravitySampler {
 public:
  using PlaceArm = std::function<void(const Vec3d& vertex_m)>;

  /// std::invalid_argument for an unusable configuration.
  GravitySampler(Device& device, Side side, const ArmCalibration& calibration,
                 const GravitySamplerConfig& config, PlaceArm place);

  /// One tick at device time now_ns (strictly increasing): read, decide,
  /// write. Returns true while sampling goes on; false once finished (then it
  /// writes zero force on every call).
  bool Tick(int64_t now_ns);

  bool finished() const { return state_ == State::kDone || state_ == State::kFailed; }
  const GravitySampleReport& report() const { return report_; }
  int vertex_count() const { return static_cast<int>(order_.size()); }
  /// Vertex currently being sampled (visiting order), vertex_count() when done.
  int current_vertex() const { return current_; }

 private:
  enum class State { kStartVertex, kRefine, kDone, kFailed };
  struct Sample {
    int64_t t_ns = 0;
    Vec3d p{};
  };

  void StartVertex(int64_t now_ns);
  void Fail(const std::string& why);
  /// Displacement per second over the last `window_ns` (history since the vertex started).
  Vec3d VelocityOver(int64_t window_ns) const;
  void WriteForce(const Vec3d& newtons);

  Device& device_;
  Side side_;
  ArmCalibration calibration_;
  GravitySamplerConfig config_;
  PlaceArm place_;
  std::vector<std::array<int, 3>> order_;  ///< snake order over the grid
  std::vector<Sample> history_;            ///< ring buffer
  std::size_t history_head_ = 0;           ///< next write
  std::size_t history_size_ = 0;
  State state_ = State::kStartVertex;
  int current_ = 0;
  Vec3d target_{};
  double force_limit_ = 0.0;  ///< N: min(max_force_n, device wrist force limit)
  double force_z_ = 0.0;
  int64_t vertex_start_ns_ = 0;
  int64_t next_decision_ns_ = 0;
  int64_t hold_start_ns_ = -1;
  int64_t first_ns_ = -1;
  int decisions_ = 0;
  GravitySampleReport report_;
};

}  // namespace haptel::haptics
