#include "haptel/interfaces/key_level.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace haptel::interfaces {

KeyLevel::KeyLevel(int min_level, int max_level, double repeat_s, bool release_to_zero)
    : min_(min_level), max_(max_level), repeat_s_(repeat_s), release_to_zero_(release_to_zero) {
  if (min_level > 0 || max_level < 0 || !(repeat_s > 0.0)) {
    throw std::invalid_argument("KeyLevel: expected min_level <= 0 <= max_level and repeat_s > 0");
  }
}

void KeyLevel::Skip(uint32_t plus_presses, uint32_t minus_presses) {
  seen_plus_ = plus_presses;
  seen_minus_ = minus_presses;
}

int KeyLevel::Clamp(long level) const {
  return static_cast<int>(std::clamp<long>(level, min_, max_));
}

void KeyLevel::set_level(int level) { level_ = Clamp(level); }

void KeyLevel::Step(double t_s, bool plus_held, bool minus_held, uint32_t plus_presses,
                    uint32_t minus_presses) {
  // Unsigned differences: correct across counter wrap-around.
  const uint32_t new_plus = plus_presses - seen_plus_;
  const uint32_t new_minus = minus_presses - seen_minus_;
  seen_plus_ = plus_presses;
  seen_minus_ = minus_presses;
  level_ = Clamp(static_cast<long>(level_) + static_cast<long>(std::min<uint32_t>(new_plus, 1000)) -
                 static_cast<long>(std::min<uint32_t>(new_minus, 1000)));

  // Both keys held cancel out: no repeat either way.
  const int held = plus_held == minus_held ? 0 : (plus_held ? 1 : -1);
  if (new_plus + new_minus > 0 || held != held_) {
    // A fresh press (or a change of direction) restarts the typematic clock.
    next_repeat_s_ = t_s + repeat_s_;
  } else if (held != 0 && t_s >= next_repeat_s_) {
    // Every repeat period that passed since the last one steps once, so the
    // ramp does not depend on the session rate.
    const double periods = std::floor((t_s - next_repeat_s_) / repeat_s_) + 1.0;
    const int steps = static_cast<int>(std::min(periods, 2.0 * (max_ - min_) + 2.0));
    level_ = Clamp(static_cast<long>(level_) + static_cast<long>(held) * steps);
    next_repeat_s_ += periods * repeat_s_;
  }
  held_ = held;

  // A press seen this tick counts even if already released: it returns to
  // zero on the next tick, not before the command carried it.
  if (release_to_zero_ && !plus_held && !minus_held && new_plus + new_minus == 0) level_ = 0;
}

}  // namespace haptel::interfaces
