// The time-domain passivity observer and controller, on hand-computed ticks,
// in the servo loop, and in the device file.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/passivity.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "scripted_device.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr double kT = 0.001;  // s
constexpr int64_t kMs = 1'000'000;

/// The first tick: the port renders `force` along x; nothing has moved yet.
PassivityAction Start(PassivityController& pc, double force) {
  return pc.Update({force, 0, 0}, {0, 0, 0}, {0, 0, 0}, kT);
}
}  // namespace

TEST_CASE("passivity: a port that generates energy is damped back to zero observed energy") {
  PassivityController pc(PassivityLimits{100.0, 0.01});
  CHECK_FALSE(Start(pc, 2.0).acted);
  // The port pushed the hand with 2 N along +x and the hand moved 1 mm that
  // way at 1 m/s: the virtual side gave 2 N * 1 mm = 2 mJ, E = -0.002 J.
  // alpha = 0.002 / (0.001 * 1^2) = 2 N*s/m, a force of -2 N, dissipating
  // T * alpha * v^2 = 2 mJ: E back to zero.
  const PassivityAction a = pc.Update({2.0, 0, 0}, {0.001, 0, 0}, {1.0, 0, 0}, kT);
  CHECK(a.acted);
  CHECK(a.alpha[0] == Approx(2.0));
  CHECK(a.damping_force[0] == Approx(-2.0));
  CHECK(a.dissipated == Approx(0.002));
  CHECK(pc.energy()[0] == Approx(0.0).margin(1e-15));
  // The other axes neither moved nor pushed: left alone.
  CHECK(a.alpha[1] == 0.0);
  CHECK(a.alpha[2] == 0.0);
}

TEST_CASE("passivity: a port that dissipates is left alone") {
  PassivityController pc(PassivityLimits{100.0, 0.01});
  Start(pc, -2.0);
  // The port resisted the motion (-2 N against +1 mm): it absorbed 2 mJ.
  const PassivityAction a = pc.Update({-2.0, 0, 0}, {0.001, 0, 0}, {1.0, 0, 0}, kT);
  CHECK_FALSE(a.acted);
  CHECK(a.damping_force[0] == 0.0);
  CHECK(pc.energy()[0] == Approx(0.002));
  // Giving 1.5 mJ of it back leaves the port passive (E = 0.5 mJ): still alone.
  const PassivityAction b = pc.Update({2.0, 0, 0}, {-0.00075, 0, 0}, {-0.75, 0, 0}, kT);
  CHECK_FALSE(b.acted);
  CHECK(pc.energy()[0] == Approx(0.0005));
}

TEST_CASE("passivity: the v^2 floor keeps alpha finite near rest") {
  PassivityController pc(PassivityLimits{1000.0, 0.1});
  Start(pc, 2.0);
  // 2 mJ generated, but the hand is now all but still (1 cm/s < the 10 cm/s floor):
  // alpha = 0.002 / (0.001 * 0.1^2) = 200 N*s/m, not 0.002 / (0.001 * 0.01^2) = 20000.
  const PassivityAction a = pc.Update({2.0, 0, 0}, {0.001, 0, 0}, {0.01, 0, 0}, kT);
  CHECK(a.acted);
  CHECK(a.alpha[0] == Approx(200.0));
  CHECK(a.dissipated == Approx(kT * 200.0 * 1e-4));
  CHECK(pc.energy()[0] == Approx(-0.002 + kT * 200.0 * 1e-4));  // the rest waits for motion
  // At rest exactly: the floor still bounds alpha, and the force is zero.
  const PassivityAction b = pc.Update({0.0, 0, 0}, {0, 0, 0}, {0, 0, 0}, kT);
  CHECK(std::isfinite(b.alpha[0]));
  CHECK(b.damping_force[0] == 0.0);
}

TEST_CASE("passivity: alpha is capped at the device's maximum damping") {
  PassivityController pc(PassivityLimits{1.0, 0.01});
  Start(pc, 2.0);
  const PassivityAction a = pc.Update({2.0, 0, 0}, {0.001, 0, 0}, {1.0, 0, 0}, kT);
  CHECK(a.alpha[0] == Approx(1.0));  // 2 asked, 1 allowed
  CHECK(a.damping_force[0] == Approx(-1.0));
  CHECK(pc.energy()[0] == Approx(-0.001));  // half the deficit dissipated
}

TEST_CASE(
    "passivity: a sampled spring leaks energy through the hold and the controller takes it back") {
  // x(n) = A sin(w n T) against F = -k x: the force held over each period
  // lags the motion, so the observer sees the spring generate k/2 * dx^2 a
  // tick (Colgate's leak). Without a controller E drifts below zero.
  const double k = 2000.0, amplitude = 0.005, w = 2.0 * M_PI * 10.0;
  PassivityController observed(PassivityLimits{0.0, 0.01});  // cap 0: observer only
  PassivityController controlled(PassivityLimits{100.0, 0.01});
  double previous = 0.0, dissipated = 0.0;
  for (int n = 0; n <= 100; ++n) {  // one period: the spring stores nothing net
    const double x = amplitude * std::sin(w * n * kT);
    const double v = amplitude * w * std::cos(w * n * kT);
    observed.Update({-k * x, 0, 0}, {x - previous, 0, 0}, {v, 0, 0}, kT);
    dissipated += controlled.Update({-k * x, 0, 0}, {x - previous, 0, 0}, {v, 0, 0}, kT).dissipated;
    previous = x;
  }
  CHECK(observed.energy()[0] < -1e-4);
  CHECK(dissipated > 1e-4);
  CHECK(controlled.energy()[0] > observed.energy()[0]);
}

namespace {
DeviceConfig Immediate(bool passivity) {
  DeviceConfig c;
  c.safety.soft_start_s = 0.0;
  c.safety.max_force_rate = 1e6;
  c.safety.wrist_force_limit = 100.0;
  c.servo.realtime_priority = 0;
  c.servo.lock_memory = false;
  c.servo.passivity = passivity;
  return c;
}
DeviceCalibration Identity() {
  DeviceCalibration c;
  for (auto& a : c.arms) a.tracker_scale = {1, 1, 1};
  return c;
}
}  // namespace

TEST_CASE(
    "passivity in the servo loop: the coupling port's leak is damped, and only when it is on") {
  for (const bool on : {false, true}) {
    INFO("passivity " << (on ? "on" : "off"));
    test::ScriptedDevice dev;
    dev.description_.wrist_force_limit = 100.0;
    Hal hal(Identity());
    ServoLoop loop(dev, hal, Immediate(on), Identity());
    ForceSetpoint sp;
    sp.coupling_enabled = true;
    sp.coupling_stiffness = 2000.0;
    double damping_seen = 0.0;  // the largest command beyond the spring
    for (int n = 1; n <= 400; ++n) {
      const double x = 0.005 * std::sin(2.0 * M_PI * 10.0 * n * 1e-3);
      dev.position[1] = {x, 0, 0};
      hal.SetSetpoint(Side::kRight, sp, n * kMs);
      loop.Tick(Side::kRight, n * kMs);
      damping_seen = std::max(damping_seen, std::abs(dev.wrist_command[1][0] + 2000.0 * x));
    }
    const ServoCounters c = loop.Counters(Side::kRight);
    if (on) {
      CHECK(c.passivity_ticks > 0);
      CHECK(c.passivity_dissipated_j > 0.0);
      CHECK(c.passivity_max_alpha > 0.0);
      CHECK(c.passivity_max_alpha <= DeviceConfig{}.servo.passivity_max_damping);
      CHECK(damping_seen > 0.0);  // the damping changed the command
    } else {
      CHECK(c.passivity_ticks == 0);
      CHECK(c.passivity_dissipated_j == 0.0);
      CHECK(damping_seen == Approx(0.0).margin(1e-9));
    }
  }
}

TEST_CASE("servo.passivity in the device file: on or off, nothing else") {
  const auto dir = test::ScratchDir("passivity-config");
  auto load = [&](const std::string& servo) {
    return LoadDevice(test::WriteFile(dir / "d.yaml", "name: d\nservo:\n" + servo));
  };
  CHECK_FALSE(load("  rate_hz: 1000\n").servo.passivity);
  const DeviceConfig on =
      load("  passivity: on\n  passivity_max_damping: 35\n  passivity_min_speed: 0.004\n");
  CHECK(on.servo.passivity);
  CHECK(on.servo.passivity_max_damping == 35.0);
  CHECK(on.servo.passivity_min_speed == 0.004);
  CHECK_FALSE(load("  passivity: off\n").servo.passivity);
  CHECK_THROWS_WITH(load("  passivity: true\n"),
                    Catch::Contains("servo.passivity") && Catch::Contains("on or off"));
  CHECK_THROWS_WITH(load("  passivity_max_damping: -1\n"),
                    Catch::Contains("servo.passivity_max_damping"));
  CHECK_THROWS_WITH(load("  passivity_min_speed: 0\n"),
                    Catch::Contains("servo.passivity_min_speed"));
}
