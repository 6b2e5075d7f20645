#include "haptel/core/clock.hpp"

#include <atomic>
#include <cerrno>
#include <ctime>

namespace haptel {
namespace {
int64_t Read(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}
/// The simulated clock's time; 0: off (MonotonicNs reads CLOCK_MONOTONIC).
std::atomic<int64_t> simulated_ns{0};
}  // namespace

int64_t MonotonicNs() {
  const int64_t simulated = simulated_ns.load(std::memory_order_relaxed);
  return simulated != 0 ? simulated : Read(CLOCK_MONOTONIC);
}
int64_t RealMonotonicNs() { return Read(CLOCK_MONOTONIC); }
void SetSimulatedNs(int64_t now_ns) {
  simulated_ns.store(now_ns > 0 ? now_ns : 1, std::memory_order_relaxed);
}
void StopSimulatedClock() { simulated_ns.store(0, std::memory_order_relaxed); }
bool SimulatedClockOn() { return simulated_ns.load(std::memory_order_relaxed) != 0; }
int64_t WallNs() { return Read(CLOCK_REALTIME); }
double ThreadCpuSeconds() { return NsToS(Read(CLOCK_THREAD_CPUTIME_ID)); }

void SleepUntilNs(int64_t monotonic_ns) {
  timespec ts{};
  ts.tv_sec = monotonic_ns / 1'000'000'000;
  ts.tv_nsec = monotonic_ns % 1'000'000'000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace haptel
