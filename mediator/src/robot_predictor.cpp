#include "haptel/mediator/robot_predictor.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

namespace haptel::mediator {

RobotPredictor::RobotPredictor(const TreadDriveConfig& drive, double watchdog_s, double step_s,
                               PredictionModel model)
    : drive_(drive), model_(model), estimator_(drive), watchdog_s_(watchdog_s), step_s_(step_s) {}

void RobotPredictor::Localise(const Track& track, const LocaliserConfig& config) {
  // Learning, the map as built is learnt too (it is part of what differs
  // from the files); the nominal model keeps the file's.
  LocaliserConfig used = config;
  if (model_ == PredictionModel::kLearn) used.learn_map = true;
  localiser_.emplace(track, used);
}

void RobotPredictor::BlendIn(const Pose2& odometry, double sample_s) {
  // Nothing to blend until there is a localised pose to blend from: the
  // odometry (or the localiser's first pose) is shown as it is.
  if (!blending_ || !localiser_ || !localiser_->started()) {
    shown_pose_ = pose_;
    blend_odometry_ = odometry;
    blend_s_ = sample_s;
    blending_ = localiser_ && localiser_->started();
    return;
  }
  // The shown pose moves by the odometry's increment (in the robot's frame)...
  const double dx = odometry.x - blend_odometry_.x, dy = odometry.y - blend_odometry_.y;
  const double c0 = std::cos(blend_odometry_.heading), s0 = std::sin(blend_odometry_.heading);
  const double along = c0 * dx + s0 * dy, across = -s0 * dx + c0 * dy;
  const double c = std::cos(shown_pose_.heading), s = std::sin(shown_pose_.heading);
  shown_pose_.x += c * along - s * across;
  shown_pose_.y += s * along + c * across;
  shown_pose_.heading += std::remainder(odometry.heading - blend_odometry_.heading, 2.0 * M_PI);
  // ...and is drawn to the localised pose at the blends' rates (a state
  // sampled before the last one, jitter's, moves nothing).
  const double dt = std::max(0.0, sample_s - blend_s_);
  const double to_position = 1.0 - std::exp(-dt / kPositionBlendS);
  const double to_heading = 1.0 - std::exp(-dt / kHeadingBlendS);
  shown_pose_.x += (pose_.x - shown_pose_.x) * to_position;
  shown_pose_.y += (pose_.y - shown_pose_.y) * to_position;
  shown_pose_.heading +=
      std::remainder(pose_.heading - shown_pose_.heading, 2.0 * M_PI) * to_heading;
  blend_odometry_ = odometry;
  blend_s_ = std::max(blend_s_, sample_s);
}

void RobotPredictor::OnRoundTrip(double rtt_s) {
  if (keep_inputs_) inputs_.round_trips_s.push_back(rtt_s);
  dating_.AddRoundTrip(rtt_s);
  delay_.AddRoundTrip(rtt_s);
}

void RobotPredictor::OnCommand(double t_s, double left, double right) {
  if (keep_inputs_) inputs_.commands.push_back({t_s, left, right});
  commands_.push_back({t_s, models::QuantiseCommand(left, drive_.speed_levels),
                       models::QuantiseCommand(right, drive_.speed_levels)});
}

double RobotPredictor::OnState(const RobotStateSample& state) {
  if (keep_inputs_) inputs_.states.push_back(state);
  const double d = delay_.one_way_s();
  // Its stamp on the operator's clock (the offset by the minimum filter).
  const double sample_s = dating_.SampleTime(state.received_s, state.stamp_s, d);
  // Where the state says the robot is: its odometry, localised on the track
  // once there are ranges to do it with.
  const Pose2 odometry{state.x, state.y, state.heading};
  pose_ = odometry;
  if (localiser_ && (state.ranges.count > 0 || localiser_->started()))
    pose_ = localiser_->Update(pose_, state.ranges, state.touching);
  BlendIn(odometry, sample_s);
  located_.push_back({sample_s, pose_.x, pose_.y, 0.0});
  odometry_.push_back({sample_s, state.x, state.y, 0.0});
  // What the operator was shown of this moment at this moment: the
  // prediction from the newest state it had then.
  double error_m = -1.0;
  const Base* known = nullptr;
  for (const Base& b : bases_) {  // by sample: the newest that had arrived
    if (b.received_s <= sample_s && b.sample_s <= sample_s) known = &b;
  }
  if (known != nullptr) {
    std::vector<PredictedPose> predicted;
    Run(*known, nullptr, {sample_s}, predicted);
    error_m = std::hypot(predicted.front().x - pose_.x, predicted.front().y - pose_.y);
    errors_m_.push_back(error_m);
  }
  // Then what the state teaches, for the predictions from now on.
  estimator_.Observe({state.stamp_s != 0.0 ? state.stamp_s : state.received_s, state.speed,
                      state.yaw_rate, state.applied_left, state.applied_right, state.touching});
  if (estimator_.gains_known() && gains_known_s_ < 0.0) gains_known_s_ = state.received_s;
  if (estimator_.width_known() && width_known_s_ < 0.0) width_known_s_ = state.received_s;
  if (model_ == PredictionModel::kLearn) drive_ = estimator_.Drive();
  Base base{state.received_s,
            sample_s,
            {shown_pose_.x, shown_pose_.y, shown_pose_.heading, 0.0, 0.0},
            state.applied_left,
            state.applied_right};
  models::TreadsFromMotion(drive_, state.speed, state.yaw_rate, base.treads);
  // In sample order: a state sampled before one that arrived ahead of it (a
  // vehicle's state jitter: harsh's, one state in eleven) is not the
  // newest, and the model runs on from the newest. Kept by arrival, the
  // prediction went back to the older state until the next arrived, a
  // state period's more to extrapolate and a jump in the ghost each time.
  auto at = bases_.end();
  while (at != bases_.begin() && std::prev(at)->sample_s > sample_s) --at;
  bases_.insert(at, base);
  // A state is needed while no later sampled one had arrived by the newest's sample.
  while (bases_.size() > 1 && bases_[1].received_s <= sample_s) bases_.pop_front();
  // Commands that took effect before the oldest state kept are in its
  // applied levels; a second's margin for a late state.
  while (!commands_.empty() && commands_.front().sent_s + d < bases_.front().sample_s - 1.0)
    commands_.pop_front();
  const PredictedPose now = PoseAt(state.received_s);
  shown_.push_back({now.t_s, now.x, now.y, 0.0});
  return error_m;
}

void RobotPredictor::Run(const Base& base, const Command* extra, const std::vector<double>& at,
                         std::vector<PredictedPose>& out) const {
  const double d = delay_.one_way_s();
  models::TreadState s = base.treads;
  double t = base.sample_s;
  int left = base.left;
  int right = base.right;
  // The robot stops `watchdog_s_` after the last command reached it; the
  // command being given (`extra`) is taken as given on and on.
  double last_arrival = base.sample_s;
  bool held = false;
  auto advance = [&](double to) {
    while (t < to - 1e-12) {
      const double stop_s =
          held ? std::numeric_limits<double>::infinity() : last_arrival + watchdog_s_;
      double end = std::min(to, t + step_s_);
      const bool stopped = t >= stop_s;
      if (!stopped && end > stop_s) end = stop_s;
      models::StepTreads(drive_, stopped ? 0.0 : models::LevelSpeed(drive_, left),
                         stopped ? 0.0 : models::LevelSpeed(drive_, right), end - t, s);
      t = end;
    }
  };
  size_t next_time = 0;
  auto emit_until = [&](double limit) {
    while (next_time < at.size() && at[next_time] <= limit) {
      advance(std::max(at[next_time], base.sample_s));
      out.push_back({at[next_time], s.x, s.y, s.heading});
      ++next_time;
    }
  };
  auto apply = [&](const Command& c, bool is_extra) {
    const double arrival = c.sent_s + d;
    if (arrival <= base.sample_s) return;  // in the state's applied levels already
    if (next_time == at.size()) return;    // every pose wanted is out
    emit_until(arrival);
    advance(arrival);
    left = c.left;
    right = c.right;
    last_arrival = arrival;
    held = is_extra;
  };
  for (const Command& c : commands_) apply(c, false);
  if (extra != nullptr) apply(*extra, true);
  emit_until(std::numeric_limits<double>::infinity());
}

PredictedPose RobotPredictor::PoseAt(double t_s) const {
  if (bases_.empty()) return {t_s, 0.0, 0.0, 0.0};
  std::vector<PredictedPose> out;
  Run(bases_.back(), nullptr, {t_s}, out);
  return out.front();
}

void RobotPredictor::PathAhead(double now_s, double horizon_s, double left, double right,
                               std::vector<PredictedPose>& path, double spacing_s) const {
  path.clear();
  if (bases_.empty() || !(spacing_s > 0.0)) return;
  std::vector<double> at;
  for (double t = now_s; t <= now_s + horizon_s + 1e-9; t += spacing_s) at.push_back(t);
  const Command given{now_s, models::QuantiseCommand(left, drive_.speed_levels),
                      models::QuantiseCommand(right, drive_.speed_levels)};
  Run(bases_.back(), &given, at, path);
}

}  // namespace haptel::mediator
