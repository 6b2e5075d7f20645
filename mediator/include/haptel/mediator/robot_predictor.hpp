#pragma once
/// @file The predictive display's model of the tank robot: where the robot
/// is now, and where the command being given takes it, from states that are
/// a link's delay old and the commands sent since.
///
/// A state says where the robot was when it was sampled, its treads' speeds
/// (from its speed and yaw rate) and the speed levels it had applied. The
/// predictor starts from it and replays every command sent after, each from
/// the moment it reaches the robot (sent + the one-way delay), through the
/// robot's drive model (models/tread_drive.hpp), including the robot's
/// watchdog stopping it when commands stop. The model's numbers are the
/// vehicle file's (PredictionModel::kNominal) or, with kLearn, the file's
/// with each tread's gain and the effective track width as estimated from
/// the states so far, once known (DriveEstimator, drive_estimator.hpp). The
/// estimator runs either way, so that a run with the nominal model still
/// says what it would have learnt.
/// Walls are not modelled: a robot pressed against one is predicted to move
/// on, and the next state corrects it.
///
/// Where a state says the robot is: its odometry, or — once Localise gave
/// the predictor the track and states carry range scans — its odometry
/// corrected by the scan against the track's walls and posts
/// (TrackLocaliser, track_localiser.hpp). That pose is what each state's
/// error is measured against, and pose(). A state
/// without ranges before any with leaves the odometry as it is (the CAN
/// robot: nothing changes); once localising, a state without a scan moves
/// the corrected pose by its odometry alone.
///
/// The model starts not from that pose itself but from the pose shown: the
/// localiser's corrections are blended in rather than stepped, as a
/// networked game's predicted view blends in the server's corrections over
/// a short time rather than snapping (Valve's Source engine: prediction
/// error smoothing, cl_smoothtime; Bernier, "Latency Compensating Methods",
/// GDC 2001): the shown pose moves by each state's odometry increment and
/// is drawn to the localised pose with a time constant, the position's
/// kPositionBlendS, the heading's kHeadingBlendS (a complementary filter:
/// the gyro's heading over seconds, the scans' beyond; harsh's gyro drifts
/// ~1 mrad/s, the learning localiser's heading steps 1.3 mrad rms a state).
/// Stepped with each scan, the learnt map's pose cost the automatic
/// operator 0.48 s a lap on harsh at 0 ms (a longer, wavier path at the
/// same speeds); blended, 0.20 s, within the seeds' spread; the nominal
/// model's error against the truth is 3-5 mm larger for it
/// (docs/benchmarks.md). Odometry alone is shown as it is.
///
/// The one-way delay is half the command round trip's running median
/// (DelayEstimate, delay_estimate.hpp). A state stamped by the vehicle is
/// dated by its stamp on the operator's clock (StampDating, shared with
/// the blimp's predictor): the vehicle's clock is its
/// own, so its offset is estimated as the smallest arrival less stamp over
/// the last few seconds less half the smallest round trip (the minimum
/// filter of clock synchronisation: the fastest state crossed in the
/// fastest one-way time). A state that a loaded host delivered late is
/// then taken for as old as it is, not as fresh as its arrival says. An
/// unstamped state is dated by its arrival less the one-way delay.
///
/// Each state that arrives is compared with what the predictor said, at the
/// moment the state was sampled, of that moment (from the states it had
/// then: a delay's extrapolation): errors_m(), a fitted model's figure of
/// merit. Each time a state arrives, the pose the operator is then shown
/// as the robot now is kept (shown()): scored against the truth after the
/// run (prediction.hpp).
#include <array>
#include <deque>
#include <optional>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/delay_estimate.hpp"
#include "haptel/mediator/drive_estimator.hpp"
#include "haptel/mediator/prediction.hpp"
#include "haptel/mediator/track_localiser.hpp"
#include "haptel/models/tread_drive.hpp"

namespace haptel::mediator {

/// A pose at a time on the operator's clock (s).
struct PredictedPose {
  double t_s = 0.0;
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
};

class RobotPredictor {
 public:
  /// `watchdog_s`: the robot stops this long after the last command reached
  /// it. `step_s`: the model's integration step. `model`: the file's
  /// numbers alone, or with what is learnt.
  explicit RobotPredictor(const TreadDriveConfig& drive, double watchdog_s = 0.2,
                          double step_s = 0.005, PredictionModel model = PredictionModel::kNominal);

  /// From now on, states with range scans are localised on `track` (its
  /// walls and posts are copied: it may go); with kLearn, the localiser
  /// learns the map as built as it drives (LocaliserConfig::learn_map).
  void Localise(const Track& track, const LocaliserConfig& config = {});
  /// The localiser, once Localise was called (null otherwise).
  const TrackLocaliser* localiser() const { return localiser_ ? &*localiser_ : nullptr; }

  /// A command as sent at `t_s` (normalised tread commands in [-1, 1], as
  /// the link carries them; the robot quantises them to its levels).
  void OnCommand(double t_s, double left, double right);
  /// A command round trip (s).
  void OnRoundTrip(double rtt_s);
  /// A state arrived. Returns the distance (m) between its pose and the pose
  /// the predictor gave for that moment at that moment (negative when no
  /// state had arrived by then: nothing was predicted), and records it in
  /// errors_m().
  double OnState(const RobotStateSample& state);

  bool ready() const { return !bases_.empty(); }
  /// The one-way delay in use (s).
  double one_way_delay_s() const { return delay_.one_way_s(); }
  /// The robot's pose at `t_s` (the present, or any time after the newest
  /// state's sample), with the commands sent so far.
  PredictedPose PoseAt(double t_s) const;
  /// The path from `now_s` over `horizon_s`: the commands still on their
  /// way, then `left`/`right` held from now on; a pose every `spacing_s`,
  /// the first at now (appended to `path`, which is cleared first).
  void PathAhead(double now_s, double horizon_s, double left, double right,
                 std::vector<PredictedPose>& path, double spacing_s = 0.05) const;
  /// The newest state's pose: its odometry, or localised (see above).
  const Pose2& pose() const { return pose_; }
  /// The pose shown and predicted from: pose() with the localiser's
  /// corrections blended in (see above).
  const Pose2& shown_pose() const { return shown_pose_; }
  /// The blends' time constants (s).
  static constexpr double kPositionBlendS = 0.3;
  static constexpr double kHeadingBlendS = 2.0;
  /// Each state's pose as the predictor took it (localised or not) and its
  /// odometry alone, at the moment it was sampled (operator's clock:
  /// arrival less the one-way delay): scored against the truth after the
  /// run (prediction_score.hpp).
  const std::vector<ShownPose>& located() const { return located_; }
  const std::vector<ShownPose>& odometry() const { return odometry_; }
  /// Every state's prediction error so far (m), against its pose.
  const std::vector<double>& errors_m() const { return errors_m_; }
  /// The pose shown as the robot now, each time a state arrived.
  const std::vector<ShownPose>& shown() const { return shown_; }
  /// What is learnt of the drive (used by the model with kLearn).
  const DriveEstimator& estimator() const { return estimator_; }
  /// From now on, every input is kept (inputs()).
  void KeepInputs() { keep_inputs_ = true; }
  const RobotPredictorInputs& inputs() const { return inputs_; }
  /// The drive the model runs now.
  const TreadDriveConfig& drive() const { return drive_; }
  /// When (operator's clock, s) the gains and the track width first became
  /// known (negative: not yet).
  double gains_known_s() const { return gains_known_s_; }
  double width_known_s() const { return width_known_s_; }

 private:
  struct Command {
    double sent_s;
    int left;  ///< levels, as the robot quantises them
    int right;
  };
  /// A state as the model starts from it.
  struct Base {
    double received_s;
    double sample_s;  ///< when it was sampled (operator's clock)
    models::TreadState treads;
    int left;
    int right;
  };
  /// Runs the model from `base` through the commands sent, and `extra` (if
  /// given) after them, held on; appends the pose at each time of `at`
  /// (ascending) to `out`.
  void Run(const Base& base, const Command* extra, const std::vector<double>& at,
           std::vector<PredictedPose>& out) const;

  TreadDriveConfig drive_;
  PredictionModel model_;
  DriveEstimator estimator_;
  double watchdog_s_;
  double step_s_;
  DelayEstimate delay_;
  StampDating dating_;  ///< the vehicle clock's offset (see above)
  std::deque<Command> commands_;
  /// The states since the one the operator had when the newest was
  /// sampled (that one's prediction is the newest's error), in the order
  /// they were sampled (not arrived), the newest sampled last: the one the
  /// model runs on from.
  std::deque<Base> bases_;
  std::vector<double> errors_m_;
  std::vector<ShownPose> shown_;
  std::optional<TrackLocaliser> localiser_;
  /// Moves shown_pose_ by the odometry's increment and draws it to pose_.
  void BlendIn(const Pose2& odometry, double sample_s);

  Pose2 pose_;
  Pose2 shown_pose_;
  Pose2 blend_odometry_;  ///< the odometry at the last blend
  double blend_s_ = 0.0;  ///< its sample time
  bool blending_ = false;
  std::vector<ShownPose> located_;
  std::vector<ShownPose> odometry_;
  double gains_known_s_ = -1.0, width_known_s_ = -1.0;
  bool keep_inputs_ = false;
  RobotPredictorInputs inputs_;
};

}  // namespace haptel::mediator
