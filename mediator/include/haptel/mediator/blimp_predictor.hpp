#pragma once
/// @file The predictive display's model of the blimp: where the blimp is
/// now (position, height, heading), and where the command being given takes
/// it, from states that are a link's delay old and the commands sent since.
/// The blimp's counterpart of RobotPredictor (robot_predictor.hpp), built
/// the same way.
///
/// A state says where the blimp was when it was sampled: its position,
/// attitude (yaw, pitch, roll), ground velocity and the channels it had
/// applied. The predictor starts the simulated blimp (models/sim_blimp.hpp: the
/// airship model and its contacts with the course's ground and buildings,
/// the vehicle file's numbers — what the simulated vehicle flies) from it
/// and replays every command sent after the one it had applied (the state
/// echoes that one's send time), each from the moment it reaches the blimp
/// (sent + the one-way delay, and not before the state), including the
/// blimp's watchdog
/// putting every channel to neutral when commands stop. What a state does
/// not carry is taken from the model:
///
/// - the body's angular rates: from the turn between the state and the one
///   before (on the vehicle's clock, its stamps), the rate over the last
///   state period;
/// - the actuators' own state (the motors' thrust as spun up, the helix
///   plane as slewed, the tail rotor's thrust): from the model run on from
///   the state before (the commands' history drives them alone); at the
///   first state, settled at the applied channels.
///
/// The wind is the vehicle file's mean wind (PredictionModel::kNominal), or
/// with kLearn the steady wind estimated while the blimp flies, once known:
/// a constant disturbance, learnt by recursive least squares
/// (recursive_least_squares.hpp) on the velocity residual, with exponential
/// forgetting: the steady-state equivalent of a Kalman filter with the wind
/// as a random-walk state (Ljung and Söderström, *Theory and Practice of
/// Recursive Identification*, 1983, ch. 2.6; Ljung and Gunnarsson 1990),
/// its process noise set by the forgetting factor (a 20-s memory). At each state
/// the model is run from the state before — the commands timed as the
/// state's echo says they arrived, not by the delay, lest a loaded link's
/// jitter read as wind — with the estimate ŵ (the prior: the file's wind,
/// worth a standard deviation of 3 m/s) and with ŵ nudged east and north: the residual r (measured
/// ground velocity less the model's, horizontal) is linear in the wind's error through the nudges'
/// sensitivity J, r ≈ J (w − ŵ), two scalar measurements a state. No update while the model touches
/// the ground or a building (friction, not the air, holds it) nor across a gap in the states. Known
/// once each component's standard deviation is under kWindKnown_mps. Gusts cannot be foreseen (the
/// model runs without them): they show in the error, and their mean over the estimator's memory (20
/// s) in the estimate. The estimator runs with either model, so that a nominal run still says what
/// it would have learnt.
///
/// The one-way delay is half the command round trip's running median
/// (DelayEstimate). A stamped state is dated by its stamp on the operator's
/// clock as the robot's are (StampDating, delay_estimate.hpp: the clocks'
/// offset from the least delayed of the last states less half the
/// smallest round trip; a busy receiver only ever adds to a state's
/// latency, and at 6 m/s each 10 ms of it would be 6 cm of error). It was
/// dated by the least arrival less stamp over a second less half the
/// *median* round trip: on a jittery link the median's excess over the
/// fastest made every state older than it was by half of it. Each state that arrives is compared
/// with what the predictor said, at the moment the state was sampled, of that moment (from the
/// states it had then: a delay's extrapolation): errors_m(), the 3-D distance between the two
/// centres of gravity (horizontal and height error together: both matter to a blimp among
/// buildings).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include "haptel/config/airship.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/mediator/delay_estimate.hpp"
#include "haptel/mediator/prediction.hpp"
#include "haptel/mediator/recursive_least_squares.hpp"
#include "haptel/models/sim_blimp.hpp"

namespace haptel::mediator {

/// A blimp state as the predictor needs it (what BlimpState carries).
struct BlimpStateSample {
  double received_s = 0.0;  ///< when it arrived, operator's clock
  /// When it was sampled, the vehicle's clock (its sample time on the
  /// operator's, and rates from two states); 0: unknown (arrival less the delay).
  int64_t stamp_ns = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< centre of gravity, course frame, m
  double yaw = 0.0;                                    ///< rad, counter-clockwise from +x
  double pitch = 0.0;                                  ///< rad, nose up positive
  double roll = 0.0;                                   ///< rad, right side down positive
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< ground velocity, course frame, m/s
  BlimpCommand
      applied;  ///< the channels in effect when it was sampled (the failsafe's neutral included)
  /// When the command in effect was sent (operator's clock, as the state
  /// echoes it): the commands sent after it are the ones to replay.
  /// Negative: no echo (those whose arrival, sent + the delay, is after the
  /// sample are replayed).
  double command_sent_s = -1.0;
  /// How long the command in effect had been held when the state was
  /// sampled (s; the watchdog counts from its arrival); negative: unknown
  /// (taken as just arrived).
  double command_age_s = -1.0;
};

/// The blimp at a time on the operator's clock (s).
struct BlimpPredictedPose {
  double t_s = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< centre of gravity, m (z: height)
  double yaw = 0.0;                                    ///< heading, rad
  double pitch = 0.0;                                  ///< rad
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< ground velocity, course frame, m/s
  double airspeed = 0.0;                               ///< m/s
  bool contact = false;                                ///< touching the ground or a building
};

class BlimpPredictor {
 public:
  /// `airship`, `course`: the vehicle file's model and the course flown
  /// (validated: ConfigFieldError). `watchdog_s`: every channel goes to
  /// neutral this long after the last command reached the blimp. `model`:
  /// the file's wind, or the one estimated once known.
  BlimpPredictor(const AirshipConfig& airship, const BlimpCourseConfig& course,
                 double watchdog_s = 0.2, PredictionModel model = PredictionModel::kNominal);

  /// A wind component is known once its standard deviation is under this (m/s).
  static constexpr double kWindKnown_mps = 0.2;

  /// A command as sent at `t_s` (the blimp clamps it as it applies it).
  void OnCommand(double t_s, const BlimpCommand& command);
  /// A command round trip (s).
  void OnRoundTrip(double rtt_s) {
    delay_.AddRoundTrip(rtt_s);
    dating_.AddRoundTrip(rtt_s);
  }
  /// A state arrived. Returns the distance (m) between its centre of gravity
  /// and where the predictor put it for that moment at that moment
  /// (negative when no state had arrived by then: nothing was predicted),
  /// and records it in errors_m().
  double OnState(const BlimpStateSample& state);

  bool ready() const { return !bases_.empty(); }
  /// The one-way delay in use (s).
  double one_way_delay_s() const { return delay_.one_way_s(); }
  /// The blimp at `t_s` (the present, or any time after the newest state's
  /// sample), with the commands sent so far.
  BlimpPredictedPose PoseAt(double t_s) const;
  /// The path from `now_s` over `horizon_s`: the commands still on their
  /// way, then `given` held from now on; a pose every `spacing_s`, the
  /// first at now (into `path`, which is cleared first).
  void PathAhead(double now_s, double horizon_s, const BlimpCommand& given,
                 std::vector<BlimpPredictedPose>& path, double spacing_s = 0.1) const;
  /// Every state's prediction error so far (m, 3-D), against its own
  /// reported position.
  const std::vector<double>& errors_m() const { return errors_m_; }
  /// The pose shown as the blimp now, each time a state arrived.
  const std::vector<ShownPose>& shown() const { return shown_; }
  /// The steady horizontal wind estimated (world frame, m/s; the file's
  /// until known), and when it first was (operator's clock, s; negative:
  /// not yet).
  Eigen::Vector2d wind() const;
  bool wind_known() const { return wind_known_s_ >= 0.0; }
  double wind_known_s() const { return wind_known_s_; }
  int wind_updates() const { return wind_updates_; }

 private:
  struct Command {
    double sent_s;
    BlimpCommand command;
  };
  /// A state as the model starts from it.
  struct Base {
    double received_s;
    double sample_s;  ///< when it was sampled (operator's clock)
    int64_t stamp_ns;
    models::AirshipState state;
    BlimpCommand applied;
    double applied_sent_s;   ///< when the applied command was sent; negative: no echo
    double applied_since_s;  ///< when the applied command reached the blimp (operator's clock)
  };
  /// What a state says had reached the blimp by its sample: the command it
  /// echoes, sent at `sent_s`, arrived at `arrival_s` (operator's clock);
  /// none sent after it.
  struct Arrived {
    double sent_s;
    double arrival_s;
  };
  /// Runs the model from `base` through the commands sent, and `extra` (if
  /// given) after them, held on; calls `emit` with the model at each time of
  /// `at` (ascending). With `arrived` (a run up to a state's sample), the
  /// commands arrive as that state says, not at the delay's estimate.
  void Run(const Base& base, const Command* extra, const std::vector<double>& at,
           const std::function<void(double, const models::SimBlimp&)>& emit,
           const Arrived* arrived = nullptr) const;
  /// What `state`, sampled at `sample_s`, says had arrived; null without an echo.
  static const Arrived* ArrivedBy(const BlimpStateSample& state, double sample_s,
                                  const Base& before, Arrived& out);
  static BlimpPredictedPose PoseOf(double t_s, const models::SimBlimp& model);
  /// When `state` was sampled, operator's clock (s), with the delay `d`;
  /// notes its latency for those after.
  double SampleTime(const BlimpStateSample& state, double d);
  /// The wind estimator's update from `state`, sampled at `sample_s`, with
  /// the model run from `before`.
  void UpdateWind(const Base& before, double sample_s, const BlimpStateSample& state);

  AirshipConfig airship_;
  PredictionModel model_kind_;
  double watchdog_s_;
  /// The steady wind the replays fly (the file's, or the estimate), world, m/s.
  Eigen::Vector3d replay_wind_;
  RecursiveLeastSquares2 wind_;
  double wind_known_s_ = -1.0;
  int wind_updates_ = 0;
  /// The model the replays run on (set to each replay's start): scratch,
  /// hence mutable; a predictor is used from one thread.
  mutable models::SimBlimp model_;
  DelayEstimate delay_;
  StampDating dating_;  ///< the vehicle clock's offset (SampleTime)
  std::deque<Command> commands_;
  /// The states since the one the operator had when the newest was
  /// sampled (that one's prediction is the newest's error), newest last.
  std::deque<Base> bases_;
  std::vector<double> errors_m_;
  std::vector<ShownPose> shown_;
};

}  // namespace haptel::mediator
