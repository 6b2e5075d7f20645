#pragma once
/// @file What the robot's and the blimp's predictors share beyond the delay
/// (delay_estimate.hpp): the model they run ahead (the vehicle file's alone,
/// or with what they learn of the vehicle while it drives), the record of
/// what they showed, and its score.
///
/// A prediction is scored twice:
/// - against the vehicle's own states (odometry): each state that arrives
///   against what the predictor said of its moment at its moment. The
///   model's fit to what the vehicle reports; blind to what the vehicle
///   does not know of itself (its odometry's drift, a slip it cannot see);
/// - against the truth: each pose the operator was shown as the vehicle now
///   (`ShownPose`, one a state) against where the vehicle truly was then,
///   from the simulated vehicle's truth record, read after the run only.
#include <cstddef>
#include <functional>
#include <string_view>
#include <vector>

#include "haptel/core/range_scan.hpp"

namespace haptel::mediator {

/// The model a predictor runs ahead of the delayed states.
enum class PredictionModel {
  kNominal,  ///< the vehicle file's numbers
  kLearn,    ///< the file's, with what is estimated of the vehicle once known
};

/// "nominal" or "learn".
std::string_view PredictionModelName(PredictionModel model);

/// Where the predictor put the vehicle for the moment `t_s` (the operator's
/// clock, s from the run's start), as it was then shown.
struct ShownPose {
  double t_s = 0.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;  ///< height (the blimp); 0 for the robot
};

/// A vehicle state as the predictor needs it.
struct RobotStateSample {
  double received_s = 0.0;  ///< when it arrived, operator's clock
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
  double speed = 0.0;     ///< m/s, forward
  double yaw_rate = 0.0;  ///< rad/s
  int applied_left = 0;   ///< speed levels in effect when it was sampled
  int applied_right = 0;
  /// When it was sampled, the vehicle's clock (s; intervals between states
  /// for the estimator); 0: unknown (its arrival is used).
  double stamp_s = 0.0;
  bool touching = false;  ///< a bumper pressed
  /// Its range scan (count 0: the vehicle has none), from the same moment.
  RangeScan ranges{};
};

/// Everything a robot's predictor consumed, in order, when asked to keep it
/// (RobotPredictor::KeepInputs; SessionSetup::keep_predictor_inputs): what
/// shows that it reads nothing but what crossed the link.
struct RobotPredictorInputs {
  struct Command {
    double sent_s;  ///< operator's clock
    double left, right;
  };
  std::vector<Command> commands;
  std::vector<double> round_trips_s;
  std::vector<RobotStateSample> states;
};

/// Percentiles of errors (m), by nearest rank; -1 without any.
struct ErrorPercentiles {
  double p50 = -1.0;
  double p95 = -1.0;
  size_t count = 0;
};
ErrorPercentiles PercentilesOf(std::vector<double> errors_m);

/// Where the vehicle truly was at `t_s` (the operator's clock, s from the
/// run's start), into `x`, `y`, `z`; false outside what the truth covers.
using TruthAt = std::function<bool(double t_s, double& x, double& y, double& z)>;

/// Each shown pose against the truth at its moment: the horizontal distance,
/// or with `with_height` the 3-D one (the blimp). Poses the truth does not
/// cover are left out.
ErrorPercentiles ScoreAgainstTruth(const std::vector<ShownPose>& shown, const TruthAt& truth_at,
                                   bool with_height);

}  // namespace haptel::mediator
