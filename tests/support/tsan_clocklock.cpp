/// @file pthread_mutex_clocklock for the ThreadSanitizer build's tests
/// (HAPTEL_SANITIZE=thread; tests/CMakeLists.txt links it into each test
/// program, never into a product one).
///
/// Fast DDS (and libstdc++'s timed mutexes on the steady clock) lock with
/// pthread_mutex_clocklock, which GCC 12's libtsan does not intercept: TSan
/// would see their unlocks without the locks ("unlock of an unlocked
/// mutex"), and races on everything handed over under those mutexes. This
/// definition in the executable interposes glibc's for every shared library
/// (the program exports it: -Wl,--export-dynamic-symbol) and takes the lock
/// through pthread_mutex_timedlock, which TSan does intercept, after moving
/// the deadline from the given clock to CLOCK_REALTIME. A step of the wall
/// clock during the wait moves the deadline with it: harmless in a test.
#include <pthread.h>
#include <time.h>

#include <cerrno>
#include <cstdint>

extern "C" int pthread_mutex_clocklock(pthread_mutex_t* mutex, clockid_t clock,
                                       const struct timespec* abstime) {
  if (clock == CLOCK_REALTIME) return pthread_mutex_timedlock(mutex, abstime);
  constexpr int64_t kNs = 1'000'000'000;
  // glibc's own checks: a monotonic or real-time clock, a valid time.
  if (clock != CLOCK_MONOTONIC || abstime->tv_nsec < 0 || abstime->tv_nsec >= kNs) return EINVAL;
  timespec now{}, real{};
  clock_gettime(clock, &now);
  clock_gettime(CLOCK_REALTIME, &real);
  const int64_t left_ns =
      (static_cast<int64_t>(abstime->tv_sec) - now.tv_sec) * kNs + (abstime->tv_nsec - now.tv_nsec);
  const int64_t deadline_ns = static_cast<int64_t>(real.tv_sec) * kNs + real.tv_nsec + left_ns;
  timespec deadline{};
  deadline.tv_sec = static_cast<time_t>(deadline_ns / kNs);
  deadline.tv_nsec = static_cast<long>(deadline_ns % kNs);
  return pthread_mutex_timedlock(mutex, &deadline);
}
