#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <thread>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/haptics/hal.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;
DeviceCalibration Cm() {
  DeviceCalibration c;
  for (auto& a : c.arms) {
    a.tracker_scale = {0.01, 0.01, 0.01};
    a.tracker_offset = {0.1, 0.0, -0.05};
  }
  return c;
}
WristRaw At(int64_t t_ns, const Vec3d& raw) {
  WristRaw w;
  w.t_ns = t_ns;
  w.position = raw;
  return w;
}
}  // namespace

TEST_CASE("raw values are stored and calibrated only in the accessor") {
  Hal hal(Cm());
  hal.PublishWrist(Side::kLeft, At(5, {2, 3, 4}));
  const HandSample s = hal.LatestSample(Side::kLeft);
  REQUIRE(s.valid);
  CHECK(s.position[0] == Approx(0.12));
  CHECK(s.position[1] == Approx(0.03));
  CHECK(s.position[2] == Approx(-0.01));
  TrackerSample raw[1];
  REQUIRE(hal.TrackerHistory(Side::kLeft, raw) == 1);
  CHECK(raw[0].raw[0] == 2.0);  // stored raw
}

TEST_CASE("glove angles are calibrated per sensor") {
  DeviceCalibration c;
  c.arms[1].glove_gain.fill(0.01);
  c.arms[1].glove_offset.fill(-0.2);
  Hal hal(c);
  hal.PublishWrist(Side::kRight, At(1, {0, 0, 0}));
  GloveRaw g;
  g.sensors.fill(50);
  hal.PublishGlove(Side::kRight, g);
  CHECK(hal.LatestSample(Side::kRight).finger_angles[7] == Approx(0.3));
}

TEST_CASE("the tracker keeps the last 1000 samples, oldest first") {
  Hal hal(Cm());
  for (int i = 0; i < 1500; ++i)
    hal.PublishWrist(Side::kRight, At((i + 1) * kMs, {double(i), 0, 0}));
  std::vector<TrackerSample> out(2000);
  const size_t n = hal.TrackerHistory(Side::kRight, out);
  REQUIRE(n == 1000);
  CHECK(out[0].raw[0] == 500.0);
  CHECK(out[999].raw[0] == 1499.0);
  for (size_t i = 1; i < n; ++i) CHECK(out[i].t_ns > out[i - 1].t_ns);
}

TEST_CASE("velocity by second-order backward difference is exact for quadratic motion") {
  Hal hal(Cm());
  // x(t) = 0.5 t + 2 t^2 (metres) sampled unevenly; v(t) = 0.5 + 4 t.
  const double ts[] = {0.0, 0.001, 0.0025, 0.003};
  for (double t : ts) {
    const double x = 0.5 * t + 2 * t * t;
    hal.PublishWrist(Side::kLeft, At(static_cast<int64_t>(t * 1e9), {(x - 0.1) / 0.01, 0, 0}));
  }
  const auto v = hal.TrackerVelocity(Side::kLeft);
  REQUIRE(v.has_value());
  CHECK((*v)[0] == Approx(0.5 + 4 * 0.003).epsilon(1e-6));
  CHECK_FALSE(Hal().TrackerVelocity(Side::kLeft).has_value());  // no samples yet
}

TEST_CASE("mean acceleration over a window") {
  Hal hal(Cm());
  // Constant acceleration 3 m/s^2 along y.
  for (int i = 0; i <= 400; ++i) {
    const double t = i * 1e-3;
    hal.PublishWrist(Side::kRight, At(i * kMs + 1, {0, 0.5 * 3 * t * t / 0.01, 0}));
  }
  const auto a = hal.MeanAcceleration(Side::kRight, 0.2);
  REQUIRE(a.has_value());
  CHECK((*a)[1] == Approx(3.0).epsilon(0.01));
  CHECK((*a)[0] == Approx(0.0).margin(1e-9));
}

TEST_CASE("a lost device makes the sample invalid until it returns") {
  Hal hal;
  hal.PublishWrist(Side::kRight, At(1, {0, 0, 0}));
  REQUIRE(hal.LatestSample(Side::kRight).valid);
  hal.PublishLost(Side::kRight, true);
  CHECK_FALSE(hal.LatestSample(Side::kRight).valid);
  hal.PublishLost(Side::kRight, false);
  CHECK(hal.LatestSample(Side::kRight).valid);
}

TEST_CASE("field and physics set-points live apart and combine, stamped by the older feeder") {
  Hal hal;
  ForceSetpoint sp;
  sp.finger_forces = {1, 2, 3, 4, 5};
  sp.field.enabled = true;  // ignored: fields belong to the interface
  hal.SetSetpoint(Side::kLeft, sp, 42);
  CHECK(hal.Setpoint(Side::kLeft).stamp_ns == 42);  // the field was never written: ignored
  CHECK_FALSE(hal.Setpoint(Side::kLeft).field.enabled);
  ForceField f;
  f.enabled = true;
  hal.SetField(Side::kLeft, f, 50);
  ForceSetpoint after = hal.Setpoint(Side::kLeft);
  CHECK(after.field.enabled);
  CHECK(after.finger_forces[4] == 5.0);
  CHECK(after.stamp_ns == 42);  // the older of the two
  hal.SetSetpoint(Side::kLeft, sp, 60);
  CHECK(hal.Setpoint(Side::kLeft).stamp_ns == 50);
  hal.ZeroForces();
  after = hal.Setpoint(Side::kLeft);
  CHECK_FALSE(after.field.enabled);
  CHECK(after.finger_forces[4] == 5.0);  // the physics thread's part is its own
  CHECK(after.stamp_ns == 60);
}

TEST_CASE("two feeders writing at once never tear each other's set-point") {
  Hal hal;
  std::atomic<bool> done{false};
  test::Thread physics("physics feeder", [&] {
    ForceSetpoint sp;
    for (int i = 1; i <= 100000; ++i) {
      sp.finger_forces.fill(i);
      sp.coupling_stiffness = i;
      hal.SetSetpoint(Side::kRight, sp, i);
    }
  });
  test::Thread interface("interface feeder", [&] {
    ForceField f;
    for (int i = 1; i <= 100000; ++i) {
      f.stiffness = i;
      f.damping = i;
      hal.SetField(Side::kRight, f, i);
    }
  });
  uint64_t torn = 0;
  test::Thread reader("reader", [&] {
    while (!done.load()) {
      const ForceSetpoint sp = hal.Setpoint(Side::kRight);
      if (sp.field.stiffness != sp.field.damping) ++torn;
      if (sp.coupling_stiffness != sp.finger_forces[0] ||
          sp.finger_forces[0] != sp.finger_forces[4])
        ++torn;
    }
  });
  physics.Join();
  interface.Join();
  done = true;
  reader.Join();
  CHECK(torn == 0);
  const ForceSetpoint last = hal.Setpoint(Side::kRight);
  CHECK(last.field.stiffness == 100000);
  CHECK(last.coupling_stiffness == 100000);
}

TEST_CASE("concurrent hand-off: readers never see a torn sample or history out of order") {
  Hal hal;
  std::atomic<bool> done{false};
  std::atomic<uint64_t> torn{0};
  std::atomic<uint64_t> disorder{0};
  std::atomic<uint64_t> reads{0};
  // The writer goes on until the readers have read while it wrote: on a loaded machine
  // they may not be scheduled before a fixed count of samples is through (seen in CI).
  test::Thread writer("writer", [&] {
    for (int i = 1; i <= 200000 || reads.load() < 2000; ++i) {
      const double v = i;
      hal.PublishWrist(Side::kRight, At(i, {v, v, v}));
    }
    done = true;
  });
  auto reader = [&] {
    std::vector<TrackerSample> h(64);
    while (!done.load()) {
      const HandSample s = hal.LatestSample(Side::kRight);
      if (s.valid && !(s.position[0] == s.position[1] && s.position[1] == s.position[2])) ++torn;
      const size_t n = hal.TrackerHistory(Side::kRight, h);
      for (size_t i = 0; i < n; ++i) {
        if (!(h[i].raw[0] == h[i].raw[1] && h[i].raw[1] == h[i].raw[2])) ++torn;
        if (h[i].raw[0] != static_cast<double>(h[i].t_ns)) ++torn;
        if (i > 0 && h[i].t_ns <= h[i - 1].t_ns) ++disorder;
      }
      ++reads;
    }
  };
  test::Thread r1("reader 1", reader);
  test::Thread r2("reader 2", reader);
  writer.Join();
  r1.Join();
  r2.Join();
  CHECK(reads.load() >= 2000);
  CHECK(torn.load() == 0);
  CHECK(disorder.load() == 0);
}

TEST_CASE("the HAL refuses a calibration DeviceCalibration::ValidateOrThrow refuses") {
  DeviceCalibration c;
  c.arms[1].tracker_scale[0] = std::nan("");
  CHECK_THROWS_WITH(Hal(c), Catch::Contains("arms.right.tracker_scale[0]"));
  CHECK_THROWS_AS(Hal(c), ConfigFieldError);
}
