#include "haptel/core/periodic_thread.hpp"

#include <pthread.h>

#include <algorithm>
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
  thread_ = std::thread([this] { Run(); });
}

void PeriodicThread::Stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  running_.store(false);
}

void PeriodicThread::Run() {
  pthread_setname_np(pthread_self(), options_.name.substr(0, 15).c_str());
  meter_.SetRealtime(TryRealtime(options_.realtime_priority));
  const auto period_ns = static_cast<int64_t>(std::llround(1e9 / options_.rate_hz));
  int64_t next = MonotonicNs() + period_ns;
  while (!stop_.load(std::memory_order_relaxed)) {
    SleepUntilNs(next);
    const int64_t start = MonotonicNs();
    meter_.RecordStart(start, next, period_ns);
    tick_(start);
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
