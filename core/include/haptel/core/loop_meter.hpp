#pragma once
/// @file What a periodic loop measures about itself: period distribution,
/// overruns, worst lateness. Recording is wait-free and allocation-free; any
/// thread may read Stats() while the loop runs.
#include <atomic>
#include <cstdint>

#include "haptel/core/histogram.hpp"

namespace haptel {

/// What a loop measured about itself. Plain data; safe to copy anywhere.
struct LoopStats {
  uint64_t ticks = 0;
  double elapsed_s = 0.0;
  double rate_hz = 0.0;        ///< ticks per second over the measured span
  double period_p50_us = 0.0;  ///< start-to-start period percentiles
  double period_p99_us = 0.0;
  double period_max_us = 0.0;
  uint64_t overruns = 0;  ///< ticks that started more than one period late, plus skipped ones
  double max_lateness_us = 0.0;  ///< worst start delay against the schedule
  bool realtime = false;         ///< SCHED_FIFO was granted
};

class LoopMeter {
 public:
  LoopMeter() : periods_(10.0, 2000) {}

  /// A tick started at `start_ns`, scheduled for `deadline_ns`, in a loop of `period_ns`.
  void RecordStart(int64_t start_ns, int64_t deadline_ns, int64_t period_ns);
  /// Ticks the loop skipped to re-anchor its schedule.
  void RecordSkipped(uint64_t ticks) { overruns_.fetch_add(ticks, std::memory_order_relaxed); }
  void SetRealtime(bool granted) { realtime_.store(granted); }

  LoopStats Stats() const;
  const Histogram& period_histogram() const { return periods_; }

 private:
  Histogram periods_;
  std::atomic<uint64_t> ticks_{0};
  std::atomic<uint64_t> overruns_{0};
  std::atomic<int64_t> first_ns_{0};
  std::atomic<int64_t> last_ns_{0};
  std::atomic<int64_t> max_lateness_ns_{0};
  std::atomic<bool> realtime_{false};
};

/// Asks for SCHED_FIFO at `priority` for the calling thread; true if granted.
/// Never granted in a ThreadSanitizer build (loop_meter.cpp says why).
bool TryRealtime(int priority);

/// What the threads and processes a thread starts while it is raised get.
enum class StartedThreads {
  /// Normal ones (SCHED_RESET_ON_FORK): a physics world built late, the
  /// vehicle's process.
  kNormal,
  /// Its SCHED_FIFO priority (pthread_create's default): for a library's
  /// threads that take no priority of their own (Fast DDS 2.9's receive,
  /// event and data-sharing threads; 2.13 added settings for them).
  kInherit,
};

/// The calling thread at SCHED_FIFO `priority` (where the process may) for
/// the object's lifetime, then back to what it was. For a loop that paces
/// itself (the session's, a replay's sender: kNormal; a PeriodicThread
/// earns its own, periodic_thread.hpp), or around the creation of a
/// library's threads (kInherit; a thread already at SCHED_FIFO `priority`
/// or above is then left as it is). Never lowers a thread: one at SCHED_FIFO
/// above `priority` keeps its own. Not granted under ThreadSanitizer.
class RealtimeWhile {
 public:
  explicit RealtimeWhile(int priority, StartedThreads started = StartedThreads::kNormal);
  ~RealtimeWhile();
  RealtimeWhile(const RealtimeWhile&) = delete;
  RealtimeWhile& operator=(const RealtimeWhile&) = delete;
  bool granted() const { return granted_; }

 private:
  int policy_ = 0;  ///< as sched_getscheduler gave it (with its reset-on-fork flag)
  int priority_ = 0;
  bool granted_ = false;
};

/// How many nice steps background threads (the video's encoder and decoder)
/// lower their own priority by. On a loaded host the scheduler then gives
/// the CPU first to the threads a command and a state pass through (the
/// link's receive threads, the control loop): without it a frame's encode
/// held them off for milliseconds, the command round trip's tail.
inline constexpr int kBackgroundNiceSteps = 10;

/// Lowers the calling thread's priority by `steps` nice steps (Linux's nice
/// is per thread; threads it starts afterwards inherit it, as a codec's
/// worker threads do). Never raises it (that needs privileges); false if the
/// kernel refused.
bool LowerThreadPriority(int steps);

/// The calling thread's nice value (-20 .. 19).
int ThreadNice();

}  // namespace haptel
