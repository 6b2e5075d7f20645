#include "haptel/mediator/auto_operator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace haptel::mediator {

AutoOperator::AutoOperator(const Track& track, const OperatorConfig& config,
                           const TreadDriveConfig& drive, const DriverProfile& profile,
                           int experience)
    : track_(track),
      config_(config),
      drive_(drive),
      profile_(profile),
      error_scale_(1.0 + profile.learning_gain *
                             std::exp(-std::max(0, experience) / profile.learning_trials)),
      random_(profile.seed * 0x9E3779B97F4A7C15ull +
              static_cast<uint64_t>(std::max(0, experience))),
      reaction_s_(config.reaction_delay_s) {
  config.ValidateOrThrow();
  profile.ValidateOrThrow();
}

namespace {

/// The turn response is learnt only from turns this fast (rad/s, expected):
/// slower ones are in the heading's noise.
constexpr double kMinLearntYawRate = 0.3;
/// Its memory, s of turning: about one corner.
constexpr double kTurnMemoryS = 1.0;
/// Before this much turning was seen (s) the model's response is trusted.
constexpr double kTurnSeenS = 0.5;
/// What the vehicle shows of a command after the operator decided it: the
/// arm's lag and the session's tick (s, beyond the arm time constant).
constexpr double kCommandLagS = 0.05;
/// It steers harder by at most this (a skid-steer turns as one at most
/// 1.6x wider: Mandow et al. 2007), never softer than the model says.
constexpr double kMaxTurnBoost = 1.6;
/// A post or obstacle slows it from this far ahead (m, from the body's
/// front edge to the obstacle's), to min_forward at contact.
constexpr double kSlowDistance = 0.3;

}  // namespace

void AutoOperator::LearnTurnResponse(const Observation& o) {
  if (seen_.empty()) return;
  const Observation& last = seen_.back().observation;
  const double dt = o.t_s - last.t_s;
  if (!(dt > 0.0) || dt > 0.2 || o.bumper_left || o.bumper_right) return;
  const double observed = WrapAngle(o.heading - last.heading) / dt;
  // The yaw rate asked for when what is now seen was commanded.
  const double asked_at = o.t_s - config_.arm_time_constant_s - kCommandLagS;
  double expected = 0.0;
  for (const auto& [t, rate] : decided_) {
    if (t > asked_at) break;
    expected = rate;
  }
  if (std::abs(expected) < kMinLearntYawRate) return;
  // A ratio of yaw rates, exponentially averaged over kTurnMemoryS of turning.
  const double ratio = std::clamp(observed / expected, 1.0 / kMaxTurnBoost, 1.5);
  const double a = std::min(1.0, dt / kTurnMemoryS);
  turn_response_ += (ratio - turn_response_) * a;
  turn_seen_s_ += dt;
}

double AutoOperator::ObstacleSlowdown(const Observation& o) const {
  const Vec2 p(o.x, o.y);
  const Vec2 ahead(std::cos(o.heading), std::sin(o.heading));
  const double half_width = drive_.track_width / 2.0;
  double slow = 1.0;
  for (const CircleObstacle& c : track_.round_obstacles()) {
    const Vec2 to = c.center - p;
    const double along = to.dot(ahead);
    const double aside = std::abs(to.x() * ahead.y() - to.y() * ahead.x());
    // In the band the body sweeps (its width and as much again to spare).
    if (along <= 0.0 || aside > 2.0 * half_width + c.radius) continue;
    const double gap = along - half_width - c.radius;
    slow = std::min(slow, std::clamp(gap / kSlowDistance, 0.0, 1.0));
  }
  return slow;
}

void AutoOperator::Observe(const Observation& observation) {
  LearnTurnResponse(observation);
  if (!observation.bumper_left && !observation.bumper_right) ++clears_;
  seen_.push_back({observation, clears_});
  // Keep a little more than the reaction delay's worth.
  while (seen_.size() > 2 && seen_[1].observation.t_s < observation.t_s - reaction_s_ - 0.5) {
    seen_.pop_front();
  }
}

double AutoOperator::PassingOffset(const Observation& o) const {
  // The round obstacle (post or obstacle) the robot's bumper touches, if
  // any: the nearest one within reach ahead, on the touched side.
  const Vec2 p(o.x, o.y);
  const Vec2 ahead(std::cos(o.heading), std::sin(o.heading));
  const Vec2 left(-ahead.y(), ahead.x());
  const CircleObstacle* hit = nullptr;
  double nearest = std::numeric_limits<double>::infinity();
  for (const CircleObstacle& c : track_.round_obstacles()) {
    const Vec2 to = c.center - p;
    const double gap = to.norm() - c.radius;
    const bool on_touched_side = (o.bumper_left && o.bumper_right) ||
                                 (o.bumper_left ? to.dot(left) >= 0.0 : to.dot(left) <= 0.0);
    if (to.dot(ahead) > 0.0 && on_touched_side && gap < kObstacleReach && gap < nearest) {
      nearest = gap;
      hit = &c;
    }
  }
  if (hit == nullptr) return 0.0;  // a wall: the centre line is the way
  // Pass it on the side of the corridor with more room, clear of it by the
  // robot's width.
  const double s = track_.ClosestArcLength(hit->center);
  const Vec2 tangent = track_.TangentAt(s);
  const double lateral = (hit->center - track_.PointAt(s)).dot(Vec2(-tangent.y(), tangent.x()));
  const double clearance = hit->radius + drive_.track_width;
  const double side =
      lateral > 0.0 ? -1.0
      : lateral < 0.0
          ? 1.0
          : ((p - track_.PointAt(s)).dot(Vec2(-tangent.y(), tangent.x())) < 0.0 ? -1.0 : 1.0);
  return lateral + side * clearance;
}

interfaces::MotionIntent AutoOperator::Decide(double t_s) {
  // The newest observation at least reaction_delay old.
  const Seen* seen = nullptr;
  for (const Seen& candidate : seen_) {
    if (candidate.observation.t_s <= t_s - reaction_s_) seen = &candidate;
  }
  if (seen == nullptr) return {};
  const Observation* o = &seen->observation;

  const bool touching = o->bumper_left || o->bumper_right;
  // A contact is new once the bumpers have been clear since the one that
  // started the last back-off. One that outlasts its back-off is the same
  // contact: reversing did not free the robot (something behind it, where
  // it has no bumper to tell), and reversing again would only push it there
  // for ever, short of a finish it has not crossed.
  const bool new_contact = touching && seen->clears != backoff_clears_;
  if (new_contact && !backing_off(t_s)) {
    backoff_clears_ = seen->clears;
    // Hitting again while still aiming: the last attempt had too little
    // room, so back off further each time (up to four back-offs' worth).
    repeat_contacts_ = careful(t_s) ? std::min(repeat_contacts_ + 1, 3) : 0;
    backoff_until_s_ = t_s + config_.backoff_s * (1 + repeat_contacts_);
    careful_until_s_ = backoff_until_s_ + config_.careful_s;
    // Reverse while turning away from the side that touched.
    backoff_turn_ = o->bumper_left && !o->bumper_right   ? -0.25
                    : o->bumper_right && !o->bumper_left ? 0.25
                                                         : 0.0;
    aim_offset_ = PassingOffset(*o);
  }
  if (backing_off(t_s)) {
    decided_.emplace_back(t_s, 0.0);  // reversing against what it hit: nothing to learn from
    return {-0.5, backoff_turn_};
  }

  // Pure pursuit: steer onto the arc through a point `lookahead` ahead on the
  // centre line.
  const Vec2 p(o->x, o->y);
  const double s = track_.ClosestArcLength(p);
  // Aiming after a contact, the driver looks closer ahead (tighter tracking).
  const double lookahead = careful(t_s) ? config_.lookahead / 2.0 : config_.lookahead;
  Vec2 goal = track_.PointAt(s + lookahead);
  if (careful(t_s) && aim_offset_ != 0.0) {
    // Aiming past the obstacle it hit: the centre line shifted beside it.
    const Vec2 tangent = track_.TangentAt(s + lookahead);
    goal += Vec2(-tangent.y(), tangent.x()) * aim_offset_;
  }
  const Vec2 d = goal - p;
  const double alpha = WrapAngle(std::atan2(d.y(), d.x()) - o->heading);
  // Still touching after backing off: turn on the spot, away from the
  // touched side (head-on: towards the goal), until the bumpers are clear.
  if (touching) {
    const double away = o->bumper_left && !o->bumper_right   ? -1.0
                        : o->bumper_right && !o->bumper_left ? 1.0
                                                             : std::copysign(1.0, alpha);
    decided_.emplace_back(t_s, 0.0);
    return {0.0, 0.4 * away};
  }
  const double distance = std::max(d.norm(), 1e-3);
  const double curvature = 2.0 * std::sin(alpha) / distance;
  // Slow down in turns: full cruise on straights, min_forward on an arc of
  // radius slow_radius or tighter.
  const double tightness = std::min(1.0, std::abs(curvature) * config_.slow_radius);
  double forward = config_.cruise - (config_.cruise - config_.min_forward) * tightness;
  // A post or obstacle in its way: slower as it comes near.
  forward = std::min(
      forward, config_.min_forward + (config_.cruise - config_.min_forward) * ObstacleSlowdown(*o));
  // Facing away from the goal: turn on the spot first.
  if (std::abs(alpha) > 1.2) forward = 0.0;
  const double speed = forward * drive_.max_speed;
  double turn = curvature * speed * drive_.track_width / 2.0 / drive_.max_speed;
  if (forward == 0.0) turn = std::copysign(0.4, alpha);
  // Ask for more by what the vehicle has been seen to lack, and remember the
  // yaw rate this asks of the model (a turn share of 1: the treads a whole
  // top speed apart), to compare with what comes of it.
  if (turn_seen_s_ >= kTurnSeenS) turn *= std::clamp(1.0 / turn_response_, 1.0, kMaxTurnBoost);
  turn = std::clamp(turn, -1.0, 1.0);
  decided_.emplace_back(t_s, turn * 2.0 * drive_.max_speed / drive_.track_width);
  while (decided_.size() > 2 && decided_.front().first < t_s - 1.0) decided_.pop_front();
  return {forward, turn};
}

namespace {

/// A standard normal draw (Box–Muller: the same on every standard library).
double Normal(std::mt19937_64& random) {
  const double u1 = (static_cast<double>(random() >> 11) + 0.5) * 0x1.0p-53;
  const double u2 = static_cast<double>(random() >> 11) * 0x1.0p-53;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

/// Below this, an intent axis means "at the centre".
constexpr double kCentre = 0.05;

}  // namespace

double AutoOperator::Practised(double factor) const {
  // The shortfall (1 − factor) is an error: it shrinks with practice.
  return 1.0 - std::min(0.9, (1.0 - factor) * error_scale_);
}

interfaces::MotionIntent AutoOperator::Express(double t_s, const interfaces::MotionIntent& ideal,
                                               const interfaces::MediatorInterface& interface) {
  const double dt = last_express_s_ < 0 ? 0.0 : std::max(0.0, t_s - last_express_s_);
  last_express_s_ = t_s;
  interfaces::MotionIntent out = ideal;

  // The steering wanders (an Ornstein–Uhlenbeck process: stationary spread
  // steering_noise, correlation time noise_time_s).
  const double spread = profile_.steering_noise * error_scale_;
  if (spread > 0.0 && dt > 0.0) {
    const double decay = std::exp(-dt / profile_.noise_time_s);
    wander_ = wander_ * decay + spread * std::sqrt(1.0 - decay * decay) * Normal(random_);
  }
  // Aiming after a contact, the driver's attention is on the steering.
  const bool attentive = careful(t_s);
  if (!attentive) out.turn += wander_;

  // Without a speed cue the driver holds back; with a speedometer, only for
  // the share of the time they do not read it.
  if (out.forward > 0.0 && !backing_off(t_s)) {
    const double unsure = Practised(profile_.unsure_cruise);
    const double cue = interface.ShowsSpeed() ? profile_.hud_use : 0.0;
    out.forward *= cue + (1.0 - cue) * unsure;
    // Holding virtual controls, and aiming one that stays put, the driver holds back.
    if (grasp_s_ > 0.0) out.forward *= Practised(profile_.holding_cruise);
    if (grasp_s_ > 0.0 && interface.ControlsStayPut())
      out.forward *= Practised(profile_.stay_put_cruise);
  }

  // A control that stays where it is left must be brought back to its centre
  // by aim: slower than moving it away, and it misses.
  if (interface.ControlsStayPut() && grasp_s_ > 0.0) {
    double* axes[2] = {&out.forward, &out.turn};
    double* applied[2] = {&applied_.forward, &applied_.turn};
    for (size_t k = 0; k < 2; ++k) {
      double wanted = *axes[k];
      if (std::abs(wanted) < kCentre && !attentive) {
        if (!at_centre_[k])
          centre_miss_[k] = profile_.recentre_error * error_scale_ * Normal(random_);
        at_centre_[k] = true;
        wanted += centre_miss_[k];
      } else {
        at_centre_[k] = false;
      }
      double& a = *applied[k];
      const bool towards_centre = std::abs(wanted) < std::abs(a) || wanted * a < 0.0;
      const double tau = config_.arm_time_constant_s + profile_.recentre_s * error_scale_;
      if (towards_centre && tau > 0.0) {
        a += (wanted - a) * (1.0 - std::exp(-dt / tau));
      } else {
        a = wanted;
      }
      *axes[k] = a;
    }
  }
  out.forward = std::clamp(out.forward, -1.0, 1.0);
  out.turn = std::clamp(out.turn, -1.0, 1.0);
  return out;
}

void AutoOperator::ScheduleSlip(size_t i, double t_s) {
  const double rate = profile_.slip_rate_hz * error_scale_;
  if (!(rate > 0.0)) {
    next_slip_s_[i] = 1e300;
    return;
  }
  const double u = (static_cast<double>(random_() >> 11) + 0.5) * 0x1.0p-53;
  next_slip_s_[i] = t_s - std::log(u) / rate;
}

namespace {

/// 0 → 1 with zero slope at both ends (a hand eases in and out of a motion).
double Smooth(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}

/// Normalised linear blend of two unit quaternions (the shorter way round).
std::array<double, 4> Blend(const std::array<double, 4>& from, const std::array<double, 4>& to,
                            double a) {
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

interfaces::HandTargets AutoOperator::Act(double t_s,
                                          const interfaces::MediatorInterface& interface) {
  if (start_s_ < 0) {
    const interfaces::HandTargets neutral = interface.HandTargetsFor({});
    start_s_ = t_s;
    bool grasps = false;
    for (const auto& g : neutral) grasps = grasps || (g && HasApproach(*g));
    grasp_s_ = grasps ? config_.grasp_reach_s + config_.grasp_close_s : 0.0;
    if (grasps) reaction_s_ += profile_.holding_reaction_s * error_scale_;
  }
  const double since = t_s - start_s_;
  if (!grasped(t_s)) {
    // Reach (open hand from the approach point down onto the control), then close.
    const double reach = config_.grasp_reach_s > 0 ? Smooth(since / config_.grasp_reach_s) : 1.0;
    const double close = config_.grasp_close_s > 0
                             ? Smooth((since - config_.grasp_reach_s) / config_.grasp_close_s)
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

  const interfaces::HandTargets wanted =
      interface.HandTargetsFor(Express(t_s, Decide(t_s), interface));
  const double dt = last_act_s_ < 0 ? 0.0 : t_s - last_act_s_;
  last_act_s_ = t_s;
  const double alpha =
      config_.arm_time_constant_s > 0 ? 1.0 - std::exp(-dt / config_.arm_time_constant_s) : 1.0;
  for (size_t i = 0; i < wanted.size(); ++i) {
    if (!wanted[i]) {
      arm_[i].reset();
      continue;
    }
    if (!arm_[i])
      arm_[i] = interface.HandTargetsFor({})[i];  // a hand new to the task starts at neutral
    interfaces::HandGoal& g = *arm_[i];
    for (int k = 0; k < 3; ++k) g.position[k] += (wanted[i]->position[k] - g.position[k]) * alpha;
    g.orientation = Blend(g.orientation, wanted[i]->orientation, alpha);
    g.glove = wanted[i]->glove;  // the fingers keep their grip
    g.approach = wanted[i]->approach;
  }
  // A control slips out of the hand: it opens and lifts off, then comes back
  // down and closes again, over regrasp_s; the arm goes on following the intent.
  interfaces::HandTargets out = arm_;
  for (size_t i = 0; i < out.size(); ++i) {
    if (!out[i] || !HasApproach(*out[i])) continue;
    if (next_slip_s_[i] < 0.0) ScheduleSlip(i, t_s);
    if (slip_start_s_[i] < 0.0 && t_s >= next_slip_s_[i]) {
      slip_start_s_[i] = t_s;
      ++slips_;
    }
    if (slip_start_s_[i] < 0.0) continue;
    const double a = (t_s - slip_start_s_[i]) / profile_.regrasp_s;
    if (a >= 1.0) {
      slip_start_s_[i] = -1.0;
      ScheduleSlip(i, t_s);
      continue;
    }
    const double open = a < 0.5 ? Smooth(2.0 * a) : 1.0 - Smooth(2.0 * a - 1.0);
    interfaces::HandGoal& g = *out[i];
    for (int k = 0; k < 3; ++k) g.position[k] += g.approach[k] * open;
    for (double& angle : g.glove) angle *= 1.0 - open;
  }
  return out;
}

}  // namespace haptel::mediator
