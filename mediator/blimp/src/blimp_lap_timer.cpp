#include "haptel/mediator/blimp/blimp_lap_timer.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"

namespace haptel::mediator {

BlimpLapTimer::BlimpLapTimer(const BlimpCourseConfig& course)
    : course_(Validated(course)), gates_(MakeGateFrames(course)) {
  for (int i = 0; i < static_cast<int>(gates_.size()); ++i) splits_.push_back({i, false, -1.0});
}

bool BlimpLapTimer::OnLandingGround(const BlimpObservation& o) const {
  const double dx = o.position.x() - course_.landing.centre[0],
               dy = o.position.y() - course_.landing.centre[1];
  // Near the ground: no higher than the lap's start threshold above where it rested.
  return std::hypot(dx, dy) <= course_.landing.radius &&
         o.position.z() < start_z_ + course_.takeoff_height;
}

void BlimpLapTimer::Update(const BlimpObservation& o) {
  if (!have_previous_) {
    have_previous_ = true;
    previous_ = o;
    start_z_ = o.position.z();
    last_t_ = o.t_s;
    return;
  }
  const BlimpObservation p = previous_;
  previous_ = o;
  if (finished()) return;
  last_t_ = o.t_s;
  const bool onset = o.contact && (!p.contact || o.impact_speed != p.impact_speed);

  if (!started_) {
    const double lift = start_z_ + course_.takeoff_height;
    if (o.position.z() >= lift) {
      started_ = true;
      const double dz = o.position.z() - p.position.z();
      const double f = dz > 0.0 ? std::clamp((lift - p.position.z()) / dz, 0.0, 1.0) : 1.0;
      start_t_ = p.t_s + f * (o.t_s - p.t_s);
    }
    return;  // contacts before the lap (resting, hopping on take-off) do not count
  }

  if (o.t_s - start_t_ > course_.lap_cap_s) {
    timed_out_ = true;
    end_t_ = start_t_ + course_.lap_cap_s;
    return;
  }

  // The next gate's plane, crossed forwards between the two observations.
  if (next_gate_ < gates_total()) {
    const BlimpGateFrame& g = gates_[static_cast<size_t>(next_gate_)];
    const double s0 = g.Along(p.position), s1 = g.Along(o.position);
    if (s0 < 0.0 && s1 >= 0.0) {
      const double f = s0 / (s0 - s1);
      const Eigen::Vector3d at = p.position + f * (o.position - p.position);
      const BlimpGateCrossing c = ClassifyCrossing(g, at);
      if (c != BlimpGateCrossing::kIgnored) {
        BlimpGateSplit& split = splits_[static_cast<size_t>(next_gate_)];
        split.passed = c == BlimpGateCrossing::kPassed;
        split.split_s = p.t_s + f * (o.t_s - p.t_s) - start_t_;
        ++next_gate_;
      }
    }
  }

  const bool all_gates = next_gate_ >= gates_total();
  if (onset) {
    if (o.impact_speed > course_.crash_speed) {
      crashed_ = true;
      crash_impact_ = o.impact_speed;
      end_t_ = o.t_s;
      return;
    }
    if (!(all_gates && OnLandingGround(o))) ++touches_;
  }
  if (all_gates && o.contact && OnLandingGround(o) &&
      o.velocity.norm() < course_.landing.max_speed) {
    completed_ = true;
    end_t_ = o.t_s;
  }
}

double BlimpLapTimer::lap_time_s() const {
  if (!started_) return 0.0;
  return (finished() ? end_t_ : last_t_) - start_t_;
}

int BlimpLapTimer::gates_passed() const {
  return static_cast<int>(
      std::count_if(splits_.begin(), splits_.end(),
                    [](const BlimpGateSplit& s) { return s.split_s >= 0 && s.passed; }));
}

int BlimpLapTimer::gates_missed() const {
  return static_cast<int>(
      std::count_if(splits_.begin(), splits_.end(),
                    [](const BlimpGateSplit& s) { return s.split_s >= 0 && !s.passed; }));
}

}  // namespace haptel::mediator
