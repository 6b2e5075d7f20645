// PeriodicThread: calls the tick repeatedly, stops cleanly, counts itself.
// Behaviour only: waits are generous loops, never rate or jitter bounds.
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "haptel/core/loop_meter.hpp"
#include "haptel/core/periodic_thread.hpp"

using haptel::PeriodicThread;

namespace {

// Waits (up to a generous limit, for loaded machines) until pred() holds.
bool WaitFor(const std::function<bool()>& pred,
             std::chrono::seconds limit = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!pred()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

PeriodicThread::Options Rate(double hz, std::string name = "test-loop") {
  PeriodicThread::Options o;
  o.name = std::move(name);
  o.rate_hz = hz;
  return o;
}

}  // namespace

TEST_CASE("PeriodicThread: ticks repeatedly and stops cleanly", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  std::atomic<bool> time_went_backwards{false};
  std::atomic<int64_t> last_now{0};
  PeriodicThread loop(Rate(1000.0), [&](int64_t now_ns) {
    if (now_ns <= last_now.load()) time_went_backwards.store(true);
    last_now.store(now_ns);
    calls.fetch_add(1);
  });
  CHECK_FALSE(loop.running());
  CHECK(calls.load() == 0);  // nothing runs before Start()

  loop.Start();
  CHECK(loop.running());
  REQUIRE(WaitFor([&] { return calls.load() >= 50; }));
  loop.Stop();
  CHECK_FALSE(loop.running());

  const uint64_t after_stop = calls.load();
  CHECK(after_stop >= 50);
  CHECK_FALSE(time_went_backwards.load());

  // Stop() joined the thread: no tick runs afterwards.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(calls.load() == after_stop);

  const haptel::LoopStats s = loop.Stats();
  CHECK(s.ticks == after_stop);
  // Every tick after the first records one start-to-start period.
  CHECK(loop.period_histogram().Count() == after_stop - 1);
  CHECK(s.elapsed_s > 0.0);
  CHECK(s.rate_hz > 0.0);
  CHECK(s.period_max_us > 0.0);
  CHECK(s.period_p50_us <= s.period_p99_us);
  CHECK_FALSE(s.realtime);  // not requested

  // Safe to call twice.
  loop.Stop();
  CHECK(loop.Stats().ticks == after_stop);
}

TEST_CASE("PeriodicThread: Stats().ticks matches the ticks the test counted", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  PeriodicThread loop(Rate(2000.0), [&](int64_t) { calls.fetch_add(1); });
  loop.Start();
  REQUIRE(WaitFor([&] { return calls.load() >= 10; }));
  // While running, the counter is bumped after the tick returns. Read it
  // first: the two sides of a <= may be evaluated in either order (GCC at
  // -O1, as in the TSan build, read `calls` first and saw a tick finish
  // in between).
  const uint64_t ticks = loop.Stats().ticks;
  CHECK(ticks <= calls.load());
  REQUIRE(WaitFor([&] { return calls.load() >= 30; }));
  loop.Stop();
  CHECK(loop.Stats().ticks == calls.load());
}

TEST_CASE("PeriodicThread: can be restarted after Stop", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  PeriodicThread loop(Rate(1000.0), [&](int64_t) { calls.fetch_add(1); });
  loop.Start();
  loop.Start();  // a second Start while running is a no-op
  REQUIRE(WaitFor([&] { return calls.load() >= 5; }));
  loop.Stop();
  const uint64_t first = calls.load();
  loop.Start();
  CHECK(loop.running());
  REQUIRE(WaitFor([&] { return calls.load() >= first + 5; }));
  loop.Stop();
  CHECK(loop.Stats().ticks == calls.load());
}

TEST_CASE("PeriodicThread: the destructor stops a running loop", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  {
    PeriodicThread loop(Rate(1000.0), [&](int64_t) { calls.fetch_add(1); });
    loop.Start();
    REQUIRE(WaitFor([&] { return calls.load() >= 3; }));
  }
  const uint64_t after = calls.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  CHECK(calls.load() == after);
}

TEST_CASE("PeriodicThread: Stop without Start is harmless", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  PeriodicThread loop(Rate(100.0), [&](int64_t) { calls.fetch_add(1); });
  loop.Stop();
  CHECK_FALSE(loop.running());
  CHECK(calls.load() == 0);
  CHECK(loop.Stats().ticks == 0);
  CHECK(loop.Stats().rate_hz == 0.0);
}

TEST_CASE("PeriodicThread: a tick longer than several periods counts overruns", "[periodic]") {
  std::atomic<uint64_t> calls{0};
  // 1 kHz, and the first tick takes 30 periods.
  PeriodicThread loop(Rate(1000.0), [&](int64_t) {
    if (calls.load() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(30));
    calls.fetch_add(1);
  });
  loop.Start();
  REQUIRE(WaitFor([&] { return calls.load() >= 5; }));
  loop.Stop();
  const haptel::LoopStats s = loop.Stats();
  CHECK(s.overruns > 0);
  CHECK(s.ticks == calls.load());
}

TEST_CASE("PeriodicThread: the thread carries the loop's name", "[periodic]") {
  std::atomic<bool> done{false};
  std::string seen;
  // Linux thread names hold 15 characters; longer names are cut.
  const std::string name = "haptel-test-loop-with-a-long-name";
  PeriodicThread loop(Rate(500.0, name), [&](int64_t) {
    if (done.load()) return;
    char buf[32] = {};
    pthread_getname_np(pthread_self(), buf, sizeof(buf));
    seen = buf;
    done.store(true);
  });
  loop.Start();
  REQUIRE(WaitFor([&] { return done.load(); }));
  loop.Stop();
  CHECK(seen == name.substr(0, 15));
  CHECK(loop.options().name == name);
}

TEST_CASE("PeriodicThread: an invalid rate throws", "[periodic]") {
  auto tick = [](int64_t) {};
  CHECK_THROWS_AS(PeriodicThread(Rate(0.0), tick), std::invalid_argument);
  CHECK_THROWS_AS(PeriodicThread(Rate(-100.0), tick), std::invalid_argument);
  CHECK_THROWS_AS(PeriodicThread(Rate(std::numeric_limits<double>::quiet_NaN()), tick),
                  std::invalid_argument);
  CHECK_THROWS_AS(PeriodicThread(Rate(std::numeric_limits<double>::infinity()), tick),
                  std::invalid_argument);
  CHECK_NOTHROW(PeriodicThread(Rate(1.0), tick));
}

TEST_CASE(
    "PeriodicThread: StopWithin does not wait out a tick that will not end, and joins once it has",
    "[periodic]") {
  std::atomic<bool> in_tick{false};
  std::atomic<bool> release{false};
  PeriodicThread loop(Rate(1000.0), [&](int64_t) {
    in_tick.store(true);
    WaitFor([&] { return release.load(); });  // bounded: never hangs the test
  });
  loop.Start();
  REQUIRE(WaitFor([&] { return in_tick.load(); }));
  CHECK_FALSE(loop.StopWithin(0.05));  // still inside its tick
  CHECK(loop.running());
  release.store(true);
  CHECK(loop.StopWithin(60.0));
  CHECK_FALSE(loop.running());
  CHECK(loop.StopWithin(0.0));  // already stopped
}

TEST_CASE("PeriodicThread: nice_steps lowers the loop's own thread, not the thread that made it",
          "[periodic]") {
  // A background loop (the video's) yields the CPU to the link and control
  // threads; the creator, the control loop's owner, keeps its priority.
  const int creator_nice = haptel::ThreadNice();
  std::atomic<int> seen{-100};
  PeriodicThread::Options background = Rate(500.0, "test-background");
  background.nice_steps = haptel::kBackgroundNiceSteps;
  PeriodicThread loop(background, [&](int64_t) { seen.store(haptel::ThreadNice()); });
  loop.Start();
  REQUIRE(WaitFor([&] { return seen.load() != -100; }));
  loop.Stop();
  CHECK(seen.load() == std::min(19, creator_nice + haptel::kBackgroundNiceSteps));
  CHECK(haptel::ThreadNice() == creator_nice);
}

TEST_CASE("PeriodicThread: by default the loop runs at its creator's priority", "[periodic]") {
  std::atomic<int> seen{-100};
  PeriodicThread loop(Rate(500.0), [&](int64_t) { seen.store(haptel::ThreadNice()); });
  loop.Start();
  REQUIRE(WaitFor([&] { return seen.load() != -100; }));
  loop.Stop();
  CHECK(seen.load() == haptel::ThreadNice());
}

TEST_CASE(
    "PeriodicThread: SCHED_FIFO is earned by ticks that fit their period and given up for good "
    "after a tick far too long",
    "[periodic]") {
  std::atomic<int> policy_seen{-1};
  std::atomic<int> first_policy{-1};
  std::atomic<int> ticks{0};
  std::atomic<bool> stall{false};
  PeriodicThread::Options o = Rate(100.0, "test-earn");
  o.realtime_priority = 10;
  o.earn_realtime_ticks = 3;
  o.lose_realtime_periods = 5;
  PeriodicThread loop(o, [&](int64_t) {
    int policy = 0;
    sched_param param{};
    pthread_getschedparam(pthread_self(), &policy, &param);
    policy_seen.store(policy);
    if (ticks.fetch_add(1) == 0) first_policy.store(policy);
    // One tick of 100 ms: ten periods, past the five that lose real time.
    if (stall.exchange(false)) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  });
  loop.Start();
  // The first ticks run as their creator does, before any is judged.
  REQUIRE(WaitFor([&] { return ticks.load() >= 1; }));
  CHECK(first_policy.load() == SCHED_OTHER);
  // Quick ticks earn it, where the process may have it (root, or an rtprio limit).
  const bool granted = WaitFor([&] { return loop.Stats().realtime; }, std::chrono::seconds(10));
  if (!granted) {
    loop.Stop();
    WARN("SCHED_FIFO refused here: the loop runs on at its priority");
    CHECK_FALSE(loop.realtime_given_up());
    return;
  }
  REQUIRE(WaitFor([&] { return policy_seen.load() == SCHED_FIFO; }));
  stall.store(true);
  REQUIRE(WaitFor([&] { return loop.realtime_given_up(); }));
  CHECK_FALSE(loop.Stats().realtime);
  const int after = ticks.load();
  REQUIRE(WaitFor([&] { return ticks.load() >= after + 20; }));
  loop.Stop();
  CHECK(policy_seen.load() == SCHED_OTHER);  // and it does not ask again
}

TEST_CASE("A thread raised for a while: what the threads it starts get, and back after") {
  const int before = sched_getscheduler(0);
  // The policy of a thread started now (with its reset-on-fork flag).
  auto started_policy = [] {
    int policy = -1;
    std::thread t([&] { policy = sched_getscheduler(0); });
    t.join();
    return policy;
  };
  {
    const haptel::RealtimeWhile raised(20, haptel::StartedThreads::kInherit);
    if (!raised.granted()) {
      WARN("SCHED_FIFO refused here: nothing to check");
      return;
    }
    CHECK(sched_getscheduler(0) == SCHED_FIFO);
    CHECK(started_policy() == SCHED_FIFO);  // a library's threads take it on
  }
  CHECK(sched_getscheduler(0) == before);
  {
    const haptel::RealtimeWhile raised(20);
    REQUIRE(raised.granted());
    CHECK((sched_getscheduler(0) & ~SCHED_RESET_ON_FORK) == SCHED_FIFO);
    CHECK(started_policy() == SCHED_OTHER);  // what it starts runs normal
    // Raised for a library's threads meanwhile: raised again without the
    // reset, so that they do take it on.
    // Asked for less than it has, it keeps what it has.
    {
      const haptel::RealtimeWhile inner(10, haptel::StartedThreads::kInherit);
      CHECK(inner.granted());
      CHECK(started_policy() == SCHED_FIFO);
      sched_param param{};
      sched_getparam(0, &param);
      CHECK(param.sched_priority == 20);
    }
    CHECK(started_policy() == SCHED_OTHER);
    sched_param param{};
    sched_getparam(0, &param);
    CHECK(param.sched_priority == 20);
  }
  CHECK(sched_getscheduler(0) == before);
}
