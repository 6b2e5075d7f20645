#pragma once
/// @file A thread that calls a function at a fixed rate and measures itself.
///
/// Deadlines are absolute (CLOCK_MONOTONIC, clock_nanosleep TIMER_ABSTIME), so
/// jitter never accumulates into drift. A late tick runs at once to catch up;
/// past `max_catch_up_periods` behind, the schedule re-anchors and the missed
/// ticks are counted as overruns — the loop says it could not keep its rate,
/// it does not silently slow down.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "haptel/core/histogram.hpp"

namespace haptel {

/// What a loop measured about itself. Plain data; safe to copy anywhere.
struct LoopStats {
  uint64_t ticks = 0;
  double elapsed_s = 0.0;
  double rate_hz = 0.0;         ///< ticks per second over the measured span
  double period_p50_us = 0.0;   ///< start-to-start period percentiles
  double period_p99_us = 0.0;
  double period_max_us = 0.0;
  uint64_t overruns = 0;        ///< ticks that started more than one period late
  double max_lateness_us = 0.0; ///< worst start delay against the schedule
  bool realtime = false;        ///< SCHED_FIFO was granted
};

class PeriodicThread {
 public:
  struct Options {
    std::string name = "loop";
    double rate_hz = 1000.0;
    /// Ask for SCHED_FIFO at this priority (0 = do not ask).
    int realtime_priority = 0;
    int max_catch_up_periods = 10;
  };
  /// Called once per period with the tick's start time (CLOCK_MONOTONIC ns).
  /// Must not allocate or block if the loop is a servo loop.
  using Tick = std::function<void(int64_t now_ns)>;

  PeriodicThread(Options options, Tick tick);
  ~PeriodicThread();
  PeriodicThread(const PeriodicThread&) = delete;
  PeriodicThread& operator=(const PeriodicThread&) = delete;

  void Start();
  /// Stops and joins. Safe to call twice.
  void Stop();
  bool running() const { return running_.load(); }

  LoopStats Stats() const;
  const Histogram& period_histogram() const { return periods_; }
  const Options& options() const { return options_; }

 private:
  void Run();

  Options options_;
  Tick tick_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_{false};
  Histogram periods_;
  std::atomic<uint64_t> ticks_{0};
  std::atomic<uint64_t> overruns_{0};
  std::atomic<int64_t> first_tick_ns_{0};
  std::atomic<int64_t> last_tick_ns_{0};
  std::atomic<int64_t> max_lateness_ns_{0};
  std::atomic<bool> realtime_{false};
};

}  // namespace haptel
