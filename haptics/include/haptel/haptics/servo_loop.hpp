#pragma once
/// @file The haptic servo loop: device I/O and force computation at ~1 kHz.
///
/// Each tick reads every arm, publishes the sample to the HAL, evaluates the
/// arm's force field from the HAL, guards and limits the force and writes it.
/// A tick allocates nothing, takes no lock, logs nothing: it counts.
#include <array>
#include <atomic>
#include <cstdint>

#include "haptel/config/run.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/hal.hpp"

namespace haptel::haptics {

/// Events the loop counts instead of logging.
struct ServoCounters {
  uint64_t device_lost_ticks = 0;  ///< ticks a side reported kLost (forces zeroed)
  uint64_t forces_limited = 0;     ///< forces scaled to the device limit
  uint64_t non_finite_forces = 0;  ///< NaN/Inf forces replaced by zero
};

class ServoLoop {
 public:
  /// `device` and `hal` must outlive the loop.
  ServoLoop(Device& device, Hal& hal, const ServoConfig& config);
  ~ServoLoop();

  void Start();
  void Stop();
  /// One servo cycle at time `now_ns`. Called by the loop thread; public so
  /// tests can drive it deterministically.
  void Tick(int64_t now_ns);

  LoopStats Stats() const { return thread_.Stats(); }
  const Histogram& period_histogram() const { return thread_.period_histogram(); }
  ServoCounters Counters() const;

 private:
  Device& device_;
  Hal& hal_;
  PeriodicThread thread_;
  HandSample sample_;  ///< scratch, reused every tick
  std::array<Vec3d, kSides> last_force_{};
  std::atomic<uint64_t> device_lost_ticks_{0};
  std::atomic<uint64_t> forces_limited_{0};
  std::atomic<uint64_t> non_finite_forces_{0};
};

}  // namespace haptel::haptics
