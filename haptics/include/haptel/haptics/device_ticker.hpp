#pragma once
/// @file The device time an offline procedure (`haptel calibrate`, with or
/// without `--gravity`) runs on: simulated for the sim device's unattended
/// run (each step advances it; nothing sleeps), else the monotonic clock (each
/// step sleeps until it is due), so one procedure serves both.
#include <algorithm>
#include <cstdint>

#include "haptel/core/clock.hpp"

namespace haptel::haptics {

class DeviceTicker {
 public:
  /// Simulated time starts at `start_ns`; real time at the clock's now.
  explicit DeviceTicker(bool simulated, int64_t start_ns = 1'000'000)
      : simulated_(simulated), now_(simulated ? start_ns : MonotonicNs()) {}
  /// The device time of the current step.
  int64_t now() const { return now_; }
  /// The time `step_ns` after the current step (real time: not before now).
  int64_t Next(int64_t step_ns) {
    if (simulated_) {
      now_ += step_ns;
    } else {
      SleepUntilNs(std::max(now_ + step_ns, MonotonicNs()));
      now_ = MonotonicNs();
    }
    return now_;
  }
  bool simulated() const { return simulated_; }

 private:
  bool simulated_;
  int64_t now_;
};

}  // namespace haptel::haptics
