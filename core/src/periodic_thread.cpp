#include "haptel/core/periodic_thread.hpp"

#include <pthread.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "haptel/core/clock.hpp"

namespace haptel {

PeriodicThread::PeriodicThread(Options options, Tick tick)
    : options_(std::move(options)), tick_(std::move(tick)) {
  if (!(options_.rate_hz > 0.0) || !std::isfinite(options_.rate_hz)) {
    throw std::invalid_argument("PeriodicThread '" + options_.name + "': rate_hz must be > 0");
  }
}

PeriodicThread::~PeriodicThread() { Stop(); }

void PeriodicThread::Start() {
  if (running_.exchange(true)) return;
  stop_.store(false);
  {
    std::lock_guard lock(ended_mutex_);
    ended_ = false;
  }
  thread_ = std::thread([this] {
    Run();
    std::lock_guard lock(ended_mutex_);
    ended_ = true;
    ended_cv_.notify_all();
  });
}

void PeriodicThread::Stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  running_.store(false);
}

bool PeriodicThread::StopWithin(double timeout_s) {
  stop_.store(true);
  if (!thread_.joinable()) return true;
  {
    std::unique_lock lock(ended_mutex_);
    const auto timeout = std::chrono::duration<double>(std::max(timeout_s, 0.0));
    if (!ended_cv_.wait_for(lock, timeout, [this] { return ended_; })) return false;
  }
  Stop();  // the thread has left Run: joins at once
  return true;
}

void PeriodicThread::Run() {
  pthread_setname_np(pthread_self(), options_.name.substr(0, 15).c_str());
  LowerThreadPriority(
      options_.nice_steps);  // refused: the loop still runs, at its creator's priority
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / options_.rate_hz));
  // Real time is earned by ticks that fit their period and lost for good by one far too long.
  bool realtime = false;
  bool may_earn = options_.realtime_priority > 0;
  int ticks_within = 0;
  int64_t next = MonotonicNs() + period_ns;
  while (!stop_.load(std::memory_order_relaxed)) {
    SleepUntilNs(next);
    const int64_t start = MonotonicNs();
    meter_.RecordStart(start, next, period_ns);
    tick_(start);
    const int64_t took = MonotonicNs() - start;
    if (realtime && took > options_.lose_realtime_periods * period_ns) {
      sched_param normal{};
      pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
      realtime = false;
      may_earn = false;
      meter_.SetRealtime(false);
      realtime_given_up_.store(true);
    } else if (may_earn && !realtime) {
      ticks_within = took <= period_ns ? ticks_within + 1 : 0;
      if (ticks_within >= options_.earn_realtime_ticks) {
        realtime = TryRealtime(options_.realtime_priority);
        meter_.SetRealtime(realtime);
        may_earn = false;  // asked once: refused, it runs on at its priority
      }
    }
    next += period_ns;
    const int64_t behind = MonotonicNs() - next;
    if (behind > options_.max_catch_up_periods * period_ns) {
      const int64_t skipped = behind / period_ns;
      meter_.RecordSkipped(static_cast<uint64_t>(skipped));
      next += skipped * period_ns;
    }
  }
}

}  // namespace haptel
