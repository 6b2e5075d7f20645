#pragma once
/// @file Lap timing from a vehicle's positions: start/finish line, gates in
/// order, obstacles touched.
///
/// The lap starts when the vehicle first crosses the start line forwards.
/// Each gate line (across the whole corridor) must be crossed in order: between
/// the posts it counts as passed, outside them as missed. The lap completes
/// when the vehicle crosses the start line forwards after the last gate line.
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/mediator/run_record.hpp"

namespace haptel::mediator {

class LapTimer {
 public:
  /// Keeps a reference to `track`. `contact_clear_s`: a contact counts as a new
  /// obstacle touch only after the bumper has been clear this long.
  explicit LapTimer(const Track& track, double contact_clear_s = 0.3);
  /// Judges the lap at `gates` (one for each of the track's, in order)
  /// instead of the file's: the truth's lap at the gates as built, where
  /// their posts truly stand (prediction_score.hpp).
  LapTimer(const Track& track, std::vector<Gate> gates, double contact_clear_s = 0.3);

  /// A new vehicle position at time t (s, any monotonic origin).
  void Update(double t_s, const Vec2& position);
  /// The bumper state at time t.
  void UpdateContact(double t_s, bool touching);

  bool started() const { return started_; }
  bool completed() const { return completed_; }
  /// When the vehicle crossed the start line (the lap clock's zero), in the
  /// times given to Update; meaningful once started().
  double start_t_s() const { return start_t_; }
  /// Lap time when completed, else time since the start so far (at the last update).
  double lap_time_s() const;
  int gates_total() const { return static_cast<int>(splits_.size()); }
  int gates_passed() const;
  int gates_missed() const;
  /// Index of the next gate to cross (gates_total() once all are done).
  int next_gate() const { return next_gate_; }
  int obstacles_touched() const { return touches_; }
  const std::vector<GateSplit>& splits() const { return splits_; }

 private:
  const Track& track_;
  std::vector<Gate> gates_;
  double contact_clear_s_;
  bool have_previous_ = false;
  Vec2 previous_{0, 0};
  double previous_t_ = 0.0;
  bool started_ = false;
  bool completed_ = false;
  double start_t_ = 0.0;
  double end_t_ = 0.0;
  double last_t_ = 0.0;
  int next_gate_ = 0;
  std::vector<GateSplit> splits_;
  int touches_ = 0;
  bool touching_ = false;
  double last_touch_t_ = -1e9;
};

}  // namespace haptel::mediator
