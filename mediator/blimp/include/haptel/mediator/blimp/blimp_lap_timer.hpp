#pragma once
/// @file Lap timing of the blimp course in 3-D, from observations.
///
/// The lap starts when the centre of gravity first rises takeoff_height
/// above where it was first seen (resting at the start). Each gate's plane
/// must be crossed in order, in its direction of travel: inside the opening
/// it counts as passed, outside but within 3 gate widths of its centre as
/// missed; a crossing of the plane further away, or backwards, is no
/// crossing of that gate. A contact whose impact speed exceeds crash_speed
/// is a crash and ends the lap; a slower one is an obstacle touched —
/// except the final touchdown: after the last gate, on the ground inside
/// the landing circle. The lap completes when, after the last gate, the
/// blimp is in contact with the ground inside the landing circle slower
/// than landing.max_speed. It ends unfinished at lap_cap_s.
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/blimp_course_geometry.hpp"
#include "haptel/mediator/blimp/observation.hpp"

namespace haptel::mediator {

struct BlimpGateSplit {
  int gate = 0;
  bool passed = false;
  double split_s = -1.0;  ///< since the lap started; < 0: not crossed yet
};

class BlimpLapTimer {
 public:
  /// Validates and copies the course (ConfigFieldError).
  explicit BlimpLapTimer(const BlimpCourseConfig& course);

  /// A new observation (t_s increasing). Allocation-free.
  void Update(const BlimpObservation& o);

  bool started() const { return started_; }
  /// When the lap began (the lap clock's zero), in the states' times;
  /// meaningful once started().
  double start_t_s() const { return start_t_; }
  bool completed() const { return completed_; }
  bool crashed() const { return crashed_; }
  /// The lap cap passed before completion.
  bool timed_out() const { return timed_out_; }
  /// Completed, crashed or timed out: later observations change nothing.
  bool finished() const { return completed_ || crashed_ || timed_out_; }
  /// From the start to the end when finished, else to the last update; 0 before the start.
  double lap_time_s() const;
  int gates_total() const { return static_cast<int>(splits_.size()); }
  int gates_passed() const;
  int gates_missed() const;
  /// Index of the next gate to cross (gates_total() once all are done).
  int next_gate() const { return next_gate_; }
  int obstacles_touched() const { return touches_; }
  const std::vector<BlimpGateSplit>& splits() const { return splits_; }
  /// The impact speed of the crash (m/s), 0 without one.
  double crash_speed() const { return crash_impact_; }
  /// Where the centre of gravity was first seen (the start's height), m.
  double start_height() const { return start_z_; }

 private:
  BlimpCourseConfig course_;
  std::vector<BlimpGateFrame> gates_;
  std::vector<BlimpGateSplit> splits_;
  bool have_previous_ = false;
  BlimpObservation previous_;
  double start_z_ = 0.0;
  bool started_ = false, completed_ = false, crashed_ = false, timed_out_ = false;
  double start_t_ = 0.0, end_t_ = 0.0, last_t_ = 0.0;
  int next_gate_ = 0;
  int touches_ = 0;
  double crash_impact_ = 0.0;
};

}  // namespace haptel::mediator
