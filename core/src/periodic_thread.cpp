#include "haptel/core/periodic_thread.hpp"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptel/core/clock.hpp"

namespace haptel {

PeriodicThread::PeriodicThread(Options options, Tick tick)
    : options_(std::move(options)), tick_(std::move(tick)), periods_(10.0, 2000) {
  if (!(options_.rate_hz > 0.0) || !std::isfinite(options_.rate_hz)) {
    throw std::invalid_argument("PeriodicThread '" + options_.name + "': rate_hz must be > 0");
  }
}

PeriodicThread::~PeriodicThread() { Stop(); }

void PeriodicThread::Start() {
  if (running_.exchange(true)) return;
  stop_.store(false);
  thread_ = std::thread([this] { Run(); });
}

void PeriodicThread::Stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  running_.store(false);
}

void PeriodicThread::Run() {
  pthread_setname_np(pthread_self(), options_.name.substr(0, 15).c_str());
  if (options_.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority = options_.realtime_priority;
    realtime_.store(pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0);
  }
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / options_.rate_hz));
  int64_t next = MonotonicNs() + period_ns;
  int64_t previous_start = 0;
  while (!stop_.load(std::memory_order_relaxed)) {
    SleepUntilNs(next);
    const int64_t start = MonotonicNs();
    const int64_t lateness = start - next;
    if (lateness > max_lateness_ns_.load(std::memory_order_relaxed)) {
      max_lateness_ns_.store(lateness, std::memory_order_relaxed);
    }
    if (lateness > period_ns) overruns_.fetch_add(1, std::memory_order_relaxed);
    if (previous_start != 0) {
      periods_.Record(static_cast<double>(start - previous_start) * 1e-3);
    } else {
      first_tick_ns_.store(start, std::memory_order_relaxed);
    }
    previous_start = start;
    tick_(start);
    ticks_.fetch_add(1, std::memory_order_relaxed);
    last_tick_ns_.store(start, std::memory_order_relaxed);
    next += period_ns;
    const int64_t behind = MonotonicNs() - next;
    if (behind > options_.max_catch_up_periods * period_ns) {
      const int64_t skipped = behind / period_ns;
      overruns_.fetch_add(static_cast<uint64_t>(skipped), std::memory_order_relaxed);
      next += skipped * period_ns;
    }
  }
}

LoopStats PeriodicThread::Stats() const {
  LoopStats s;
  s.ticks = ticks_.load(std::memory_order_relaxed);
  const int64_t first = first_tick_ns_.load(std::memory_order_relaxed);
  const int64_t last = last_tick_ns_.load(std::memory_order_relaxed);
  s.elapsed_s = s.ticks > 1 ? NsToS(last - first) : 0.0;
  s.rate_hz = s.elapsed_s > 0.0 ? static_cast<double>(s.ticks - 1) / s.elapsed_s : 0.0;
  s.period_p50_us = periods_.Percentile(0.50);
  s.period_p99_us = periods_.Percentile(0.99);
  s.period_max_us = periods_.MaxUs();
  s.overruns = overruns_.load(std::memory_order_relaxed);
  s.max_lateness_us = static_cast<double>(max_lateness_ns_.load(std::memory_order_relaxed)) * 1e-3;
  s.realtime = realtime_.load();
  return s;
}

}  // namespace haptel
