#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <thread>

#include "alloc_counter.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/record/session_recorder.hpp"
#include "scripted_device.hpp"
#include "seqlock_access.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;
using haptel::test::ScriptedDevice;

namespace haptel::haptics {
/// Holds the interface's field store for a side half done (Hal's friend).
struct HalTestAccess {
  static void BeginFieldStore(Hal& hal, Side side) {
    SeqlockTestAccess::BeginStore(hal.fields_[Index(side)]);
  }
  static void EndFieldStore(Hal& hal, Side side) {
    SeqlockTestAccess::EndStore(hal.fields_[Index(side)]);
  }
};
}  // namespace haptel::haptics

namespace {
constexpr int64_t kMs = 1'000'000;

/// A configuration without soft start or rate limit, so one tick shows the force.
DeviceConfig Immediate() {
  DeviceConfig c;
  c.safety.soft_start_s = 0.0;
  c.safety.max_force_rate = 1e6;  // the most SafetyConfig allows: 1000 N per 1 ms tick
  c.servo.realtime_priority = 0;
  c.servo.lock_memory = false;
  return c;
}
/// Identity calibration: raw units are metres and newtons.
DeviceCalibration Identity() {
  DeviceCalibration c;
  for (auto& a : c.arms) a.tracker_scale = {1, 1, 1};
  return c;
}
ForceField Spring(double k) {
  ForceField f;
  f.enabled = true;
  f.stiffness = k;
  return f;
}
void SetField(Hal& hal, Side side, const ForceField& f, int64_t now_ns) {
  hal.SetField(side, f, now_ns);
}
}  // namespace

TEST_CASE("a servo tick publishes the sample and applies the set-point's force") {
  ScriptedDevice dev;
  Hal hal(Identity());
  ServoLoop loop(dev, hal, Immediate(), Identity());
  dev.position[1] = {0.02, 0, 0};
  SetField(hal, Side::kRight, Spring(100), 1 * kMs);
  loop.Tick(Side::kRight, 1 * kMs);
  CHECK(dev.wrist_command[1][0] == Approx(-2.0));
  const HandSample s = hal.LatestSample(Side::kRight);
  CHECK(s.valid);
  CHECK(s.position[0] == Approx(0.02));
  CHECK(s.force[0] == Approx(-2.0));
  CHECK_FALSE(hal.LatestSample(Side::kLeft).valid);  // one-armed device: left untouched
}

TEST_CASE("calibration turns raw units into metres and newtons into device commands") {
  ScriptedDevice dev;
  DeviceCalibration cal;
  cal.arms[1].tracker_scale = {0.01, 0.01, 0.01};  // device reports cm
  cal.arms[1].tracker_offset = {0.1, 0, 0};
  cal.arms[1].force_slope = {2.0, 2.0, 2.0};  // 2 N per command unit
  Hal hal(cal);
  ServoLoop loop(dev, hal, Immediate(), cal);
  dev.position[1] = {2.0, 0, 0};  // 2 cm raw -> 0.12 m
  ForceField f = Spring(100);
  f.neutral = {0.1, 0, 0};
  SetField(hal, Side::kRight, f, 1 * kMs);
  loop.Tick(Side::kRight, 1 * kMs);
  CHECK(hal.LatestSample(Side::kRight).position[0] == Approx(0.12));
  CHECK(dev.wrist_command[1][0] == Approx(-2.0 / 2.0));  // -2 N at 2 N/unit
}

TEST_CASE("slow channels are read every N-th cycle, the wrist every cycle") {
  ScriptedDevice dev;
  Hal hal(Identity());
  DeviceConfig c = Immediate();
  c.servo.slow_channel_divider = 6;
  ServoLoop loop(dev, hal, c, Identity());
  for (int i = 1; i <= 60; ++i) loop.Tick(Side::kRight, i * kMs);
  CHECK(dev.wrist_reads[1] == 60);
  CHECK(dev.glove_reads[1] == 10);
  CHECK(loop.Counters(Side::kRight).slow_reads == 10);
  CHECK(hal.glove_samples(Side::kRight) == 10);
}

TEST_CASE("a lost device gets zero force at once, and forces ramp in again after it returns") {
  ScriptedDevice dev;
  Hal hal(Identity());
  DeviceConfig c = Immediate();
  c.safety.soft_start_s = 0.1;
  ServoLoop loop(dev, hal, c, Identity());
  dev.position[1] = {0.05, 0, 0};
  int64_t t = 0;
  for (int i = 0; i < 200; ++i) {
    t += kMs;
    SetField(hal, Side::kRight, Spring(100), t);
    loop.Tick(Side::kRight, t);
  }
  REQUIRE(dev.wrist_command[1][0] == Approx(-5.0));
  dev.status[1] = DeviceStatus::kLost;
  t += kMs;
  loop.Tick(Side::kRight, t);
  CHECK(dev.wrist_command[1][0] == 0.0);
  CHECK_FALSE(hal.LatestSample(Side::kRight).valid);
  CHECK(loop.Counters(Side::kRight).device_lost_ticks == 1);
  dev.status[1] = DeviceStatus::kOk;
  t += kMs;
  SetField(hal, Side::kRight, Spring(100), t);
  loop.Tick(Side::kRight, t);
  CHECK(std::abs(dev.wrist_command[1][0]) < 0.1);  // soft start from zero
  for (int i = 0; i < 150; ++i) {
    t += kMs;
    SetField(hal, Side::kRight, Spring(100), t);
    loop.Tick(Side::kRight, t);
  }
  CHECK(dev.wrist_command[1][0] == Approx(-5.0));
  CHECK(hal.LatestSample(Side::kRight).valid);
}

TEST_CASE("forces fade to zero within 50 ms when the set-point feeder stalls") {
  ScriptedDevice dev;
  Hal hal(Identity());
  ServoLoop loop(dev, hal, Immediate(), Identity());
  dev.position[1] = {0.05, 0, 0};
  SetField(hal, Side::kRight, Spring(100), 1 * kMs);  // the last set-point ever
  int64_t t = 1 * kMs;
  loop.Tick(Side::kRight, t);
  REQUIRE(dev.wrist_command[1][0] == Approx(-5.0));
  double at_stall_plus_10ms = 0.0;
  while (t < 1 * kMs + 50 * kMs) {
    t += kMs;
    loop.Tick(Side::kRight, t);
    if (t == 11 * kMs) at_stall_plus_10ms = dev.wrist_command[1][0];
  }
  CHECK(at_stall_plus_10ms == Approx(-5.0));  // still fresh within the timeout
  CHECK(dev.wrist_command[1][0] == 0.0);      // gone 50 ms after the last set-point
  CHECK(loop.Counters(Side::kRight).safety.stale_ticks > 0);
}

TEST_CASE("non-finite and oversized forces are made safe and counted") {
  ScriptedDevice dev;
  Hal hal(Identity());
  ServoLoop loop(dev, hal, Immediate(), Identity());
  dev.position[1] = {0.5, 0, 0};
  SetField(hal, Side::kRight, Spring(1000), 1 * kMs);  // 500 N asked
  loop.Tick(Side::kRight, 1 * kMs);
  CHECK(std::abs(dev.wrist_command[1][0]) == Approx(7.0));
  CHECK(loop.Counters(Side::kRight).safety.clamped == 1);
  ForceSetpoint sp;
  sp.wrist_force = {std::numeric_limits<double>::quiet_NaN(), 0, 0};
  hal.SetSetpoint(Side::kRight, sp, 2 * kMs);
  loop.Tick(Side::kRight, 2 * kMs);
  CHECK(dev.wrist_command[1][0] == 0.0);
  CHECK(loop.Counters(Side::kRight).safety.non_finite == 1);
}

TEST_CASE(
    "a servo tick allocates nothing, with the passivity controller off and on, recorded into a "
    "session file or not") {
  for (const bool passivity : {false, true})
    for (const bool recording : {false, true}) {
      INFO("passivity " << (passivity ? "on" : "off") << ", recording " << recording);
      ScriptedDevice dev(true, true);
      Hal hal(Identity());
      DeviceConfig config = Immediate();
      config.servo.passivity = passivity;
      ServoLoop loop(dev, hal, config, Identity());
      std::optional<record::SessionRecorder> session;
      if (recording) {
        record::SessionFileOptions options;
        options.file = test::ScratchDir("servo-session") / "ticks.mcap";
        session.emplace(options);
        loop.SetTap(&*session);
      }
      ForceField f = Spring(40);
      f.wall_active = true;
      f.wall_stiffness = 1000;
      // Shared control's guidance too (gesture-shared), the hand past its plane.
      f.guidance_active = true;
      f.guidance_point = {0.005, 0, 0};
      f.guidance_normal = {-1, 0, 0};
      f.guidance_stiffness = 150;
      f.guidance_max_force = 3;
      ForceSetpoint coupling;
      coupling.coupling_enabled = true;
      coupling.coupling_stiffness = 3000;
      for (int i = 1; i <= 10; ++i) {  // warm up
        loop.Tick(Side::kLeft, i * kMs);
        loop.Tick(Side::kRight, i * kMs);
      }
      SetField(hal, Side::kRight, f, 10 * kMs);
      const uint64_t before = test::ThreadAllocations();
      for (int i = 11; i < 2000; ++i) {
        // The hand oscillates, so the sampled springs leak and the controller acts.
        dev.position[1] = {0.01 * std::sin(i * 0.05), 0, 0};
        hal.SetSetpoint(Side::kRight, coupling, i * kMs);
        loop.Tick(Side::kLeft, i * kMs);
        loop.Tick(Side::kRight, i * kMs);
      }
      CHECK(test::ThreadAllocations() == before);
      CHECK((loop.Counters(Side::kRight).passivity_ticks > 0) == passivity);
      if (recording) {  // every tick of each arm is in the file
        const record::SessionFileReport report = session->Close();
        CHECK(report.saved);
        CHECK(report.dropped == 0);
        CHECK(report.Messages("haptel/session/servo") ==
              loop.Counters(Side::kLeft).cycles + loop.Counters(Side::kRight).cycles);
      }
    }
}

TEST_CASE(
    "a set-point store held in progress: the tick uses the last good set-point and counts it") {
  ScriptedDevice dev;
  Hal hal(Identity());
  ServoLoop loop(dev, hal, Immediate(), Identity());
  dev.position[1] = {0.02, 0, 0};
  SetField(hal, Side::kRight, Spring(100), 1 * kMs);
  loop.Tick(Side::kRight, 1 * kMs);
  REQUIRE(dev.wrist_command[1][0] == Approx(-2.0));

  // The interface thread is pre-empted half-way through its next store.
  HalTestAccess::BeginFieldStore(hal, Side::kRight);
  std::atomic<bool> ticked{false};
  std::thread servo([&] {
    loop.Tick(Side::kRight, 2 * kMs);
    ticked = true;
  });
  // Unbounded retries would spin until the writer resumes: it resumes only
  // after this wait, so a loop that retries without bound fails it.
  const bool finished = test::WaitFor([&] { return ticked.load(); }, 10.0);
  HalTestAccess::EndFieldStore(hal, Side::kRight);
  servo.join();
  CHECK(finished);
  CHECK(dev.wrist_command[1][0] == Approx(-2.0));  // the last good field's force
  CHECK(loop.Counters(Side::kRight).setpoint_read_fallbacks == 1);

  loop.Tick(Side::kRight, 3 * kMs);  // the store is done: read again, nothing counted
  CHECK(loop.Counters(Side::kRight).setpoint_read_fallbacks == 1);
  CHECK(dev.wrist_command[1][0] == Approx(-2.0));
}

TEST_CASE(
    "two-sided mode: both arms run on their own threads and meet every cycle, allocating nothing") {
  DeviceConfig c = DeviceConfig{};
  c.servo.realtime_priority = 0;
  c.servo.lock_memory = false;
  c.servo.two_sided = true;
  SimDevice dev(c, OperatorConfig{});
  dev.Place(Side::kLeft, {0, 0.1, 0});
  dev.Place(Side::kRight, {0, -0.1, 0});
  Hal hal;
  ServoLoop loop(dev, hal, c, DeviceCalibration{});
  loop.Start();
  // A loop that never ticks fails here instead of hanging the test.
  REQUIRE(test::WaitFor([&] { return loop.Stats(Side::kRight).ticks >= 100; }, 30.0));
  const uint64_t before = test::TotalAllocations();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const uint64_t after = test::TotalAllocations();
  loop.Stop();
  CHECK(after == before);
  // The rendezvous keeps the arms in lock-step: equal cycle counts.
  CHECK(loop.Counters(Side::kLeft).cycles == loop.Counters(Side::kRight).cycles);
  CHECK(loop.Stats(Side::kLeft).ticks == loop.Stats(Side::kRight).ticks);
  CHECK(loop.Counters(Side::kLeft).cycles > 100);
}

TEST_CASE("one-sided mode drives both arms from one thread") {
  DeviceConfig c = Immediate();
  c.servo.two_sided = false;
  ScriptedDevice dev(true, true);
  Hal hal(Identity());
  ServoLoop loop(dev, hal, c, Identity());
  loop.Start();
  REQUIRE(test::WaitFor([&] { return loop.Counters(Side::kLeft).cycles >= 50; }, 30.0));
  loop.Stop();
  const auto left = loop.Counters(Side::kLeft).cycles;
  const auto right = loop.Counters(Side::kRight).cycles;
  CHECK(left == right);
  CHECK(loop.Stats(Side::kLeft).ticks == loop.Stats(Side::kRight).ticks);  // the same thread
}

TEST_CASE("the servo loop refuses a device config or calibration ValidateOrThrow refuses") {
  ScriptedDevice dev;
  Hal hal(Identity());
  DeviceConfig c = Immediate();
  c.servo.slow_channel_divider = 0;
  CHECK_THROWS_WITH(ServoLoop(dev, hal, c, Identity()),
                    Catch::Contains("servo.slow_channel_divider"));
  DeviceCalibration cal = Identity();
  cal.arms[0].force_slope[1] = 0.0;
  CHECK_THROWS_WITH(ServoLoop(dev, hal, Immediate(), cal),
                    Catch::Contains("arms.left.force_slope[1]: expected a non-zero number"));
}

TEST_CASE(
    "a cue is added to the set-point's force until it ends, on each side, allocating nothing") {
  ScriptedDevice dev(true, true);
  Hal hal(Identity());
  ServoLoop loop(dev, hal, Immediate(), Identity());
  dev.position[0] = {0.02, 0, 0};
  dev.position[1] = {0.02, 0, 0};
  // The interface's spring keeps the set-point fresh and pulls back in x;
  // the cue pushes up in z on top of it.
  const Hal::Cue cue{{0.0, 0.0, 2.0}, 50 * kMs};
  const uint64_t before = test::ThreadAllocations();
  for (int side = 0; side < kSides; ++side) hal.SetCue(static_cast<Side>(side), cue);
  for (const int64_t t : {10 * kMs, 49 * kMs}) {
    for (int side = 0; side < kSides; ++side) {
      SetField(hal, static_cast<Side>(side), Spring(100), t);
      loop.Tick(static_cast<Side>(side), t);
      INFO("side " << side << " at " << t / kMs << " ms");
      CHECK(dev.wrist_command[side][0] == Approx(-2.0));
      CHECK(dev.wrist_command[side][2] == Approx(2.0));
    }
  }
  CHECK(test::ThreadAllocations() == before);
  // Over: the spring alone.
  for (int side = 0; side < kSides; ++side) {
    SetField(hal, static_cast<Side>(side), Spring(100), 50 * kMs);
    loop.Tick(static_cast<Side>(side), 50 * kMs);
    CHECK(dev.wrist_command[side][0] == Approx(-2.0));
    CHECK(dev.wrist_command[side][2] == Approx(0.0));
  }
}

TEST_CASE("the running loop keeps apart the periods of the ticks that played a cue") {
  DeviceConfig c = DeviceConfig{};
  c.servo.realtime_priority = 0;
  c.servo.lock_memory = false;
  c.servo.two_sided = true;
  SimDevice dev(c, OperatorConfig{});
  dev.Place(Side::kLeft, {0, 0.1, 0});
  dev.Place(Side::kRight, {0, -0.1, 0});
  Hal hal;
  ServoLoop loop(dev, hal, c, DeviceCalibration{});
  loop.Start();
  // No cue: no tick is the cue's.
  REQUIRE(test::WaitFor([&] { return loop.Stats(Side::kRight).ticks >= 50; }, 30.0));
  CHECK(loop.cue_period_histogram(Side::kLeft).Count() == 0);
  CHECK(loop.cue_period_histogram(Side::kRight).Count() == 0);
  // A cue that plays until it is replaced: its ticks are counted on each arm's thread.
  for (int side = 0; side < kSides; ++side) {
    hal.SetCue(static_cast<Side>(side), {{0.0, 0.0, 1.0}, MonotonicNs() + SToNs(600.0)});
  }
  REQUIRE(
      test::WaitFor([&] { return loop.cue_period_histogram(Side::kRight).Count() >= 20; }, 30.0));
  CHECK(test::WaitFor([&] { return loop.cue_period_histogram(Side::kLeft).Count() >= 20; }, 30.0));
  // Over: the count stops while the loop goes on.
  for (int side = 0; side < kSides; ++side)
    hal.SetCue(static_cast<Side>(side), {{0.0, 0.0, 1.0}, 0});
  const uint64_t ticks_at_end = loop.Stats(Side::kRight).ticks;
  REQUIRE(test::WaitFor([&] { return loop.Stats(Side::kRight).ticks >= ticks_at_end + 3; }, 30.0));
  const uint64_t cue_ticks = loop.cue_period_histogram(Side::kRight).Count();
  REQUIRE(test::WaitFor([&] { return loop.Stats(Side::kRight).ticks >= ticks_at_end + 50; }, 30.0));
  loop.Stop();
  CHECK(loop.cue_period_histogram(Side::kRight).Count() == cue_ticks);
  CHECK(cue_ticks < loop.Stats(Side::kRight).ticks);
  // Periods of a 1 kHz loop, not times since an earlier cue.
  CHECK(loop.cue_period_histogram(Side::kRight).Percentile(0.5) < 100000.0);
}
