#include "haptel/core/loop_meter.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "haptel/core/clock.hpp"

namespace haptel {

void LoopMeter::RecordStart(int64_t start_ns, int64_t deadline_ns, int64_t period_ns) {
  const int64_t lateness = start_ns - deadline_ns;
  if (lateness > max_lateness_ns_.load(std::memory_order_relaxed)) {
    max_lateness_ns_.store(lateness, std::memory_order_relaxed);
  }
  if (lateness > period_ns) overruns_.fetch_add(1, std::memory_order_relaxed);
  const int64_t last = last_ns_.load(std::memory_order_relaxed);
  if (last != 0) {
    periods_.Record(static_cast<double>(start_ns - last) * 1e-3);
  } else {
    first_ns_.store(start_ns, std::memory_order_relaxed);
  }
  last_ns_.store(start_ns, std::memory_order_relaxed);
  ticks_.fetch_add(1, std::memory_order_relaxed);
}

LoopStats LoopMeter::Stats() const {
  LoopStats s;
  s.ticks = ticks_.load(std::memory_order_relaxed);
  const int64_t first = first_ns_.load(std::memory_order_relaxed);
  const int64_t last = last_ns_.load(std::memory_order_relaxed);
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

bool LowerThreadPriority(int steps) {
  if (steps <= 0) return true;
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  const int now = ThreadNice();
  return setpriority(PRIO_PROCESS, tid, std::min(19, now + steps)) == 0;
}

int ThreadNice() {
  // getpriority may return -1 as a value: errno tells it from an error.
  errno = 0;
  const int nice = getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)));
  return errno == 0 ? nice : 0;
}

namespace {

// No thread is raised under ThreadSanitizer. Its runtime waits for its own
// spin locks with sched_yield, which lets no thread of lower priority run
// (google/sanitizers#614): a SCHED_FIFO thread spinning on such a lock held
// by a normal thread holds its core for good. CI's TSan run hung so for
// 15 min in test_session_threads, threads at the link's priority spinning.
// TSan looks for races, not at timing; the normal build tests the policies.
#if defined(__SANITIZE_THREAD__)
constexpr bool kMayRaise = false;
#else
constexpr bool kMayRaise = true;
#endif

}  // namespace

bool TryRealtime(int priority) {
  if (!kMayRaise || priority <= 0) return false;
  sched_param param{};
  param.sched_priority = priority;
  return pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
}

RealtimeWhile::RealtimeWhile(int priority, StartedThreads started)
    : policy_(sched_getscheduler(0)) {
  sched_param param{};
  if (!kMayRaise || priority <= 0 || policy_ < 0 || sched_getparam(0, &param) != 0) return;
  priority_ = param.sched_priority;
  const bool inherit = started == StartedThreads::kInherit;
  const bool fifo = (policy_ & ~SCHED_RESET_ON_FORK) == SCHED_FIFO;
  if (inherit && policy_ == SCHED_FIFO && priority_ >= priority) return;
  // (A thread raised with reset-on-fork would start its threads normal:
  // raised again here without it, and never lowered by it.)
  sched_param wanted{};
  wanted.sched_priority = fifo ? std::max(priority, priority_) : priority;
  granted_ =
      sched_setscheduler(0, inherit ? SCHED_FIFO : SCHED_FIFO | SCHED_RESET_ON_FORK, &wanted) == 0;
}

RealtimeWhile::~RealtimeWhile() {
  if (!granted_) return;
  sched_param param{};
  param.sched_priority = priority_;
  sched_setscheduler(0, policy_, &param);
}

}  // namespace haptel
