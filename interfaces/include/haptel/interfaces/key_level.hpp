#pragma once
/// @file One integer level driven by a pair of keys, as a typematic keyboard
/// steps it: each press steps once (presses are counters, so a press shorter
/// than a session tick still counts), a held key steps again every
/// `repeat_s`, both keys held cancel out. Shared by the robot's keyboard
/// (throttle, steering) and the blimp's (power, helix plane, elevator).
#include <cstdint>

namespace haptel::interfaces {

class KeyLevel {
 public:
  /// Levels run over [min_level, max_level] (min ≤ 0 ≤ max). With
  /// `release_to_zero`, the level returns to 0 on the first step at which
  /// neither key is held and no press is new.
  KeyLevel(int min_level, int max_level, double repeat_s, bool release_to_zero);

  /// Marks the presses counted so far as seen (made before the interface
  /// existed: they belong to another one).
  void Skip(uint32_t plus_presses, uint32_t minus_presses);

  /// One step at time `t_s` (s, non-decreasing) with the keys' state now.
  /// Allocation-free; counters may wrap around.
  void Step(double t_s, bool plus_held, bool minus_held, uint32_t plus_presses,
            uint32_t minus_presses);

  int level() const { return level_; }
  void set_level(int level);
  int max_level() const { return max_; }
  int min_level() const { return min_; }

 private:
  int Clamp(long level) const;

  int min_;
  int max_;
  double repeat_s_;
  bool release_to_zero_;
  int level_ = 0;
  uint32_t seen_plus_ = 0;  ///< press counters already acted on
  uint32_t seen_minus_ = 0;
  int held_ = 0;  ///< direction held at the last step: +1, −1, 0
  double next_repeat_s_ = 0.0;
};

}  // namespace haptel::interfaces
