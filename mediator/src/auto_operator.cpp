#include "haptel/mediator/auto_operator.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::mediator {

AutoOperator::AutoOperator(const Track& track, const OperatorConfig& config, const DriveConfig& drive)
    : track_(track), config_(config), drive_(drive) {}

void AutoOperator::Observe(const Observation& observation) {
  seen_.push_back(observation);
  // Keep a little more than the reaction delay's worth.
  while (seen_.size() > 2 && seen_[1].t_s < observation.t_s - config_.reaction_delay_s - 0.5) {
    seen_.pop_front();
  }
}

interfaces::DriveIntent AutoOperator::Decide(double t_s) {
  // The newest observation at least reaction_delay old.
  const Observation* o = nullptr;
  for (const Observation& candidate : seen_) {
    if (candidate.t_s <= t_s - config_.reaction_delay_s) o = &candidate;
  }
  if (o == nullptr) return {};

  const bool touching = o->bumper_left || o->bumper_right;
  if (touching && !backing_off(t_s)) {
    backoff_until_s_ = t_s + config_.backoff_s;
    // Reverse while turning away from the side that touched.
    backoff_turn_ = o->bumper_left && !o->bumper_right ? -0.25 : o->bumper_right && !o->bumper_left ? 0.25 : 0.0;
  }
  if (backing_off(t_s)) return {-0.5, backoff_turn_};

  // Pure pursuit: steer onto the arc through a point `lookahead` ahead on the
  // centre line.
  const Vec2 p(o->x, o->y);
  const double s = track_.ClosestArcLength(p);
  const Vec2 goal = track_.PointAt(s + config_.lookahead);
  const Vec2 d = goal - p;
  const double alpha = WrapAngle(std::atan2(d.y(), d.x()) - o->heading);
  const double distance = std::max(d.norm(), 1e-3);
  const double curvature = 2.0 * std::sin(alpha) / distance;
  // Slow down in turns: full cruise on straights, min_forward on an arc of
  // radius slow_radius or tighter.
  const double tightness = std::min(1.0, std::abs(curvature) * config_.slow_radius);
  double forward = config_.cruise - (config_.cruise - config_.min_forward) * tightness;
  // Facing away from the goal: turn on the spot first.
  if (std::abs(alpha) > 1.2) forward = 0.0;
  const double speed = forward * drive_.max_speed;
  double turn = curvature * speed * drive_.track_width / 2.0 / drive_.max_speed;
  if (forward == 0.0) turn = std::copysign(0.4, alpha);
  return {forward, std::clamp(turn, -0.7, 0.7)};
}

namespace {

/// 0 → 1 with zero slope at both ends (a hand eases in and out of a motion).
double Smooth(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

/// Normalised linear blend of two unit quaternions (the shorter way round).
std::array<double, 4> Blend(const std::array<double, 4>& from, const std::array<double, 4>& to, double a) {
  const double dot = from[0] * to[0] + from[1] * to[1] + from[2] * to[2] + from[3] * to[3];
  const double sign = dot < 0 ? -1.0 : 1.0;
  std::array<double, 4> q{};
  double norm = 0.0;
  for (int k = 0; k < 4; ++k) {
    q[k] = from[k] + (sign * to[k] - from[k]) * a;
    norm += q[k] * q[k];
  }
  norm = std::sqrt(norm);
  if (!(norm > 1e-12)) return to;
  for (double& v : q) v /= norm;
  return q;
}

bool HasApproach(const interfaces::HandGoal& g) {
  return g.approach[0] != 0.0 || g.approach[1] != 0.0 || g.approach[2] != 0.0;
}

}  // namespace

interfaces::HandTargets AutoOperator::Act(double t_s, const interfaces::MediatorInterface& interface) {
  if (start_s_ < 0) {
    const interfaces::HandTargets neutral = interface.HandTargetsFor({});
    start_s_ = t_s;
    bool grasps = false;
    for (const auto& g : neutral) grasps = grasps || (g && HasApproach(*g));
    grasp_s_ = grasps ? config_.grasp_reach_s + config_.grasp_close_s : 0.0;
  }
  const double since = t_s - start_s_;
  if (!grasped(t_s)) {
    // Reach (open hand from the approach point down onto the control), then close.
    const double reach = config_.grasp_reach_s > 0 ? Smooth(since / config_.grasp_reach_s) : 1.0;
    const double close =
        config_.grasp_close_s > 0 ? Smooth((since - config_.grasp_reach_s) / config_.grasp_close_s)
                                  : (since >= config_.grasp_reach_s ? 1.0 : 0.0);
    last_act_s_ = t_s;
    const interfaces::HandTargets neutral = interface.HandTargetsFor({});
    for (size_t i = 0; i < neutral.size(); ++i) {
      arm_[i] = neutral[i];
      if (!arm_[i]) continue;
      interfaces::HandGoal& g = *arm_[i];
      for (int k = 0; k < 3; ++k) g.position[k] += g.approach[k] * (1.0 - reach);
      for (double& angle : g.glove) angle *= close;
    }
    return arm_;
  }

  const interfaces::HandTargets wanted = interface.HandTargetsFor(Decide(t_s));
  const double dt = last_act_s_ < 0 ? 0.0 : t_s - last_act_s_;
  last_act_s_ = t_s;
  const double alpha =
      config_.arm_time_constant_s > 0 ? 1.0 - std::exp(-dt / config_.arm_time_constant_s) : 1.0;
  for (size_t i = 0; i < wanted.size(); ++i) {
    if (!wanted[i]) {
      arm_[i].reset();
      continue;
    }
    if (!arm_[i]) arm_[i] = interface.HandTargetsFor({})[i];  // a hand new to the task starts at neutral
    interfaces::HandGoal& g = *arm_[i];
    for (int k = 0; k < 3; ++k) g.position[k] += (wanted[i]->position[k] - g.position[k]) * alpha;
    g.orientation = Blend(g.orientation, wanted[i]->orientation, alpha);
    g.glove = wanted[i]->glove;  // the fingers keep their grip
    g.approach = wanted[i]->approach;
  }
  return arm_;
}

}  // namespace haptel::mediator
