#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "alloc_counter.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
/// A device that records what it was told and can be made to fail.
class ScriptedDevice final : public Device {
 public:
  bool HasSide(Side side) const override { return side == Side::kRight || both; }
  DeviceStatus Read(Side, int64_t now_ns, HandSample& out) override {
    out.t_ns = now_ns;
    out.valid = true;
    out.position = position;
    out.velocity = {0, 0, 0};
    return status;
  }
  DeviceStatus WriteForce(Side side, const Vec3d& force) override {
    last_force[Index(side)] = force;
    ++writes;
    return DeviceStatus::kOk;
  }
  double wrist_force_limit() const override { return 7.0; }

  bool both = false;
  DeviceStatus status = DeviceStatus::kOk;
  Vec3d position{0.0, 0.0, 0.0};
  std::array<Vec3d, 2> last_force{};
  int writes = 0;
};

ForceField Spring(double k) {
  ForceField f;
  f.enabled = true;
  f.stiffness = k;
  return f;
}
}  // namespace

TEST_CASE("a servo tick publishes the sample and applies the field's force") {
  ScriptedDevice dev;
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  dev.position = {0.02, 0, 0};
  hal.SetField(Side::kRight, Spring(100));
  loop.Tick(1000);
  CHECK(dev.last_force[1][0] == Approx(-2.0));
  const HandSample s = hal.LatestSample(Side::kRight);
  CHECK(s.valid);
  CHECK(s.t_ns == 1000);
  CHECK(s.position[0] == Approx(0.02));
  CHECK(s.force[0] == Approx(-2.0));
  CHECK_FALSE(hal.LatestSample(Side::kLeft).valid);  // one-armed device: left untouched
}

TEST_CASE("the servo loop clamps forces to the device limit and counts it") {
  ScriptedDevice dev;
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  dev.position = {0.5, 0, 0};
  hal.SetField(Side::kRight, Spring(1000));  // 500 N asked
  loop.Tick(1);
  CHECK(std::abs(dev.last_force[1][0]) == Approx(7.0));
  CHECK(loop.Counters().forces_limited == 1);
}

TEST_CASE("a non-finite force becomes zero and is counted") {
  ScriptedDevice dev;
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  dev.position = {std::numeric_limits<double>::quiet_NaN(), 0, 0};
  hal.SetField(Side::kRight, Spring(100));
  loop.Tick(1);
  CHECK(dev.last_force[1][0] == 0.0);
  CHECK(loop.Counters().non_finite_forces == 1);
  CHECK(loop.Counters().forces_limited == 0);
}

TEST_CASE("a lost device gets zero force and an invalid sample") {
  ScriptedDevice dev;
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  dev.position = {0.05, 0, 0};
  hal.SetField(Side::kRight, Spring(100));
  loop.Tick(1);
  REQUIRE(dev.last_force[1][0] != 0.0);
  dev.status = DeviceStatus::kLost;
  loop.Tick(2);
  CHECK(dev.last_force[1][0] == 0.0);
  CHECK_FALSE(hal.LatestSample(Side::kRight).valid);
  CHECK(loop.Counters().device_lost_ticks == 1);
}

TEST_CASE("zeroing the HAL's forces zeroes the device force at the next tick") {
  ScriptedDevice dev;
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  dev.position = {0.05, 0, 0};
  hal.SetField(Side::kRight, Spring(100));
  loop.Tick(1);
  hal.ZeroForces();
  loop.Tick(2);
  CHECK(dev.last_force[1][0] == 0.0);
}

TEST_CASE("a servo tick allocates nothing") {
  SimDevice dev(SimDeviceConfig{}, OperatorConfig{});
  Hal hal;
  ServoLoop loop(dev, hal, ServoConfig{});
  ForceField f = Spring(40);
  f.wall_active = true;
  f.wall_stiffness = 1000;
  hal.SetField(Side::kRight, f);
  hal.SetField(Side::kLeft, f);
  dev.SetOperatorTarget(Side::kRight, {0.05, 0.01, 0});
  loop.Tick(1'000'000);  // warm-up
  const uint64_t before = test::ThreadAllocations();
  for (int i = 2; i < 2000; ++i) loop.Tick(i * 1'000'000LL);
  CHECK(test::ThreadAllocations() == before);
}

TEST_CASE("the servo thread allocates nothing while it runs") {
  // Count allocations made on the loop thread itself, from inside a tick.
  SimDevice dev(SimDeviceConfig{}, OperatorConfig{});
  Hal hal;
  hal.SetField(Side::kRight, Spring(40));
  ServoLoop loop(dev, hal, ServoConfig{.rate_hz = 1000, .realtime_priority = 0});
  loop.Start();
  // Wait for the loop to run, then compare the process-wide count against a
  // window where only the loop thread is active (this thread just sleeps).
  while (loop.Stats().ticks < 50) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const uint64_t ticks_before = loop.Stats().ticks;
  const uint64_t before = test::TotalAllocations();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const uint64_t after = test::TotalAllocations();
  const uint64_t ticks_after = loop.Stats().ticks;
  loop.Stop();
  CHECK(ticks_after > ticks_before);
  CHECK(after == before);
}
