#include "haptel/mediator/blimp/blimp_lap_timer.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"

namespace haptel::mediator {

BlimpLapTimer::BlimpLapTimer(const BlimpCourseConfig& course)
    : course_(Validated(course)), gates_(MakeGateFrames(course)) {
  for (int i = 0; i < static_cast<int>(gates_.size()); ++i) splits_.push_back({i, false, -1.0});
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
  // Contacts begun since the last observation (none when the vehicle's count began again).
  const uint32_t onsets = o.contacts > p.contacts ? o.contacts - p.contacts : 0;

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
    const auto pass = CrossGate(gates_[static_cast<size_t>(next_gate_)], p.position, o.position);
    if (pass && pass->crossing != BlimpGateCrossing::kIgnored) {
      BlimpGateSplit& split = splits_[static_cast<size_t>(next_gate_)];
      split.passed = pass->crossing == BlimpGateCrossing::kPassed;
      split.split_s = p.t_s + pass->fraction * (o.t_s - p.t_s) - start_t_;
      ++next_gate_;
    }
  }

  const bool landing_ground =
      next_gate_ >= gates_total() && OnLandingGround(course_, o.position, start_z_);
  if (onsets > 0) {
    if (o.impact_speed > course_.crash_speed) {
      crashed_ = true;
      crash_impact_ = o.impact_speed;
      end_t_ = o.t_s;
      return;
    }
    if (!landing_ground) touches_ += static_cast<int>(onsets);
  }
  if (landing_ground && o.contact && o.velocity.norm() < course_.landing.max_speed) {
    completed_ = true;
    end_t_ = o.t_s;
  }
}

double BlimpLapTimer::lap_time_s() const {
  if (!started_) return 0.0;
  return (finished() ? end_t_ : last_t_) - start_t_;
}

int BlimpLapTimer::gates_passed() const {
  return static_cast<int>(std::count_if(splits_.begin(), splits_.end(),
                                        [](const BlimpGateSplit& s) { return s.passed; }));
}

int BlimpLapTimer::gates_missed() const { return next_gate_ - gates_passed(); }

}  // namespace haptel::mediator
