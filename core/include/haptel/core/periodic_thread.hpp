#pragma once
/// @file A thread that calls a function at a fixed rate and measures itself.
///
/// Deadlines are absolute (CLOCK_MONOTONIC, clock_nanosleep TIMER_ABSTIME), so
/// jitter never accumulates into drift. A late tick runs at once to catch up;
/// past `max_catch_up_periods` behind, the schedule re-anchors and the missed
/// ticks are counted as overruns — the loop says it could not keep its rate,
/// it does not silently slow down.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

#include "haptel/core/loop_meter.hpp"

namespace haptel {

class PeriodicThread {
 public:
  struct Options {
    std::string name = "loop";
    double rate_hz = 1000.0;
    /// Ask for SCHED_FIFO at this priority (0 = do not ask). The loop earns
    /// it: asked for only after `earn_realtime_ticks` ticks in a row each
    /// done within its period, and given up for good (Stats().realtime
    /// false again, realtime_given_up() true) after a tick longer than
    /// `lose_realtime_periods` periods. A tick stuck for seconds at
    /// SCHED_FIFO (a physics step of a scene too big for its rate) holds a
    /// core from every ordinary thread of the process — its signal
    /// handling, its link — and of the host.
    int realtime_priority = 0;
    int earn_realtime_ticks = 100;
    int lose_realtime_periods = 10;
    /// Lower the thread's priority by this many nice steps (0 = as its
    /// creator): background work such as the video's
    /// (kBackgroundNiceSteps), which must yield to the link and control.
    int nice_steps = 0;
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
  /// Asks the thread to stop after the tick in progress; does not wait.
  void RequestStop() { stop_.store(true); }
  /// Stops, waiting at most `timeout_s` for the tick in progress to return:
  /// true when the thread has ended (joined), false when it is still inside
  /// its tick (it ends after that tick; call Stop or StopWithin again).
  bool StopWithin(double timeout_s);
  bool running() const { return running_.load(); }

  LoopStats Stats() const { return meter_.Stats(); }
  /// It had SCHED_FIFO and gave it up after a tick far longer than its period.
  bool realtime_given_up() const { return realtime_given_up_.load(); }
  const Histogram& period_histogram() const { return meter_.period_histogram(); }
  const Options& options() const { return options_; }

 private:
  void Run();

  Options options_;
  Tick tick_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_{false};
  /// Set by the thread as it leaves Run (under ended_mutex_, for StopWithin).
  bool ended_ = false;
  std::mutex ended_mutex_;
  std::condition_variable ended_cv_;
  LoopMeter meter_;
  std::atomic<bool> realtime_given_up_{false};
};

}  // namespace haptel
