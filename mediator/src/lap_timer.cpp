#include "haptel/mediator/lap_timer.hpp"

#include <algorithm>
#include <utility>

namespace haptel::mediator {

namespace {
/// Time at which the motion p0->p1 (from t0 to t1) crosses `line` forwards
/// (along `forward`), if it does.
std::optional<std::pair<double, Vec2>> ForwardCrossing(const Vec2& p0, double t0, const Vec2& p1,
                                                       double t1, const Segment2& line,
                                                       const Vec2& forward) {
  if ((p1 - p0).dot(forward) <= 0.0) return std::nullopt;
  const auto c = SegmentCrossing(p0, p1, line);
  if (!c) return std::nullopt;
  return std::make_pair(t0 + c->t * (t1 - t0), Vec2(p0 + c->t * (p1 - p0)));
}
}  // namespace

LapTimer::LapTimer(const Track& track, double contact_clear_s)
    : LapTimer(track, track.gates(), contact_clear_s) {}

LapTimer::LapTimer(const Track& track, std::vector<Gate> gates, double contact_clear_s)
    : track_(track), gates_(std::move(gates)), contact_clear_s_(contact_clear_s) {
  for (int i = 0; i < static_cast<int>(gates_.size()); ++i) splits_.push_back({i, false, -1.0});
}

void LapTimer::Update(double t_s, const Vec2& position) {
  last_t_ = t_s;
  if (!have_previous_) {
    have_previous_ = true;
    previous_ = position;
    previous_t_ = t_s;
    return;
  }
  const Vec2 p0 = previous_;
  const double t0 = previous_t_;
  previous_ = position;
  previous_t_ = t_s;
  if (completed_) return;

  const Vec2 start_forward = track_.TangentAt(0.0);
  if (!started_) {
    if (auto c = ForwardCrossing(p0, t0, position, t_s, track_.start_line(), start_forward)) {
      started_ = true;
      start_t_ = c->first;
    }
    return;
  }
  const std::vector<Gate>& gates = gates_;
  if (next_gate_ < static_cast<int>(gates.size())) {
    const Gate& g = gates[next_gate_];
    if (auto c = ForwardCrossing(p0, t0, position, t_s, g.line, g.tangent)) {
      const double half_gap = (g.left_post - g.right_post).norm() / 2 - track_.config().post_radius;
      GateSplit& split = splits_[next_gate_];
      split.passed = (c->second - g.center).norm() <= half_gap;
      split.split_s = c->first - start_t_;
      ++next_gate_;
    }
    return;
  }
  if (auto c = ForwardCrossing(p0, t0, position, t_s, track_.start_line(), start_forward)) {
    completed_ = true;
    end_t_ = c->first;
  }
}

void LapTimer::UpdateContact(double t_s, bool touching) {
  if (touching) {
    if (!touching_ && t_s - last_touch_t_ >= contact_clear_s_) ++touches_;
    last_touch_t_ = t_s;
  }
  touching_ = touching;
}

double LapTimer::lap_time_s() const {
  if (!started_) return 0.0;
  return (completed_ ? end_t_ : last_t_) - start_t_;
}

int LapTimer::gates_passed() const {
  return static_cast<int>(
      std::count_if(splits_.begin(), splits_.end(), [](const GateSplit& s) { return s.passed; }));
}

int LapTimer::gates_missed() const {
  int missed = 0;
  for (int i = 0; i < next_gate_; ++i) missed += splits_[i].passed ? 0 : 1;
  return missed;
}

}  // namespace haptel::mediator
