#pragma once
/// @file Time stamps as plain 64-bit nanosecond counts.
///
/// Loops, buffers and messages carry `int64_t` nanoseconds rather than
/// std::chrono types so that they stay trivially copyable and can cross
/// threads through a seqlock and processes through DDS unchanged.
#include <cstdint>

namespace haptel {

/// Monotonic time (CLOCK_MONOTONIC) in ns: for periods, timeouts, latencies
/// measured on one host. While the process runs on a simulated clock
/// (SetSimulatedNs), its time instead.
int64_t MonotonicNs();

/// Puts the process on a simulated clock at `now_ns` (> 0), or moves it
/// there: from now on MonotonicNs() returns what this last set, and nothing
/// else moves it. For a run whose every part steps in one thread on one
/// simulated clock (`haptel run --simulated-time`): the stamps the parts
/// take themselves (a force field's, a state's arrival) are then simulated
/// time too. No thread may run that expects real time meanwhile.
void SetSimulatedNs(int64_t now_ns);
/// Back to the real clock (the simulated clock's end).
void StopSimulatedClock();
/// Whether MonotonicNs() reads a simulated clock.
bool SimulatedClockOn();
/// CLOCK_MONOTONIC whatever the simulated clock says: a simulated run's own
/// wall time (its speed-up over real time).
int64_t RealMonotonicNs();

/// Wall-clock time (CLOCK_REALTIME) in ns since the Unix epoch: only for
/// stamps compared across processes on one host (video capture time).
int64_t WallNs();

/// CPU time the calling thread has used (CLOCK_THREAD_CPUTIME_ID), s: for
/// benchmarks that report CPU per simulated second.
double ThreadCpuSeconds();

/// Sleeps until the given CLOCK_MONOTONIC time; returns at once if it passed.
void SleepUntilNs(int64_t monotonic_ns);

constexpr double NsToS(int64_t ns) { return static_cast<double>(ns) * 1e-9; }
constexpr int64_t SToNs(double s) { return static_cast<int64_t>(s * 1e9); }

}  // namespace haptel
