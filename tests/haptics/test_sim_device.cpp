#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/haptics/sim_device.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;

/// Runs the device for `seconds` at 1 kHz with a constant device force.
HandSample RunFor(SimDevice& d, Side side, int64_t& t, double seconds, const Vec3d& force) {
  HandSample s;
  const int steps = static_cast<int>(seconds * 1000);
  for (int i = 0; i < steps; ++i) {
    t += kMs;
    REQUIRE(d.Read(side, t, s) == DeviceStatus::kOk);
    d.WriteForce(side, force);
  }
  return s;
}
}  // namespace

TEST_CASE("the simulated operator moves the hand to the target") {
  SimDevice d(SimDeviceConfig{}, OperatorConfig{});
  d.Place(Side::kRight, {0, 0, 0});
  d.SetOperatorTarget(Side::kRight, {0.05, -0.02, 0});
  int64_t t = 1;
  const HandSample s = RunFor(d, Side::kRight, t, 2.0, {0, 0, 0});
  CHECK(s.valid);
  CHECK(s.position[0] == Approx(0.05).margin(0.002));
  CHECK(s.position[1] == Approx(-0.02).margin(0.002));
}

TEST_CASE("the operator pushes harder against a steady pull, but a strong force holds the hand back") {
  OperatorConfig op;
  auto error_under = [&](double pull) {
    SimDevice d(SimDeviceConfig{}, op);
    d.Place(Side::kRight, {0, 0, 0});
    d.SetOperatorTarget(Side::kRight, {0.05, 0, 0});
    int64_t t = 1;
    return 0.05 - RunFor(d, Side::kRight, t, 4.0, {-pull, 0, 0}).position[0];
  };
  // A 2 N pull back: the integral term wins the position back over time.
  const double small = error_under(2.0);
  CHECK(std::abs(small) < 0.003);
  // 7 N (the device limit) exceeds what the operator's integral can hold.
  const double large = error_under(7.0);
  CHECK(large > 0.005);
  CHECK(large > 3 * std::abs(small));
}

TEST_CASE("the device saturates commanded forces at its limit") {
  SimDeviceConfig cfg;
  cfg.force_limit = 7.0;
  SimDevice d(cfg, OperatorConfig{});
  d.Place(Side::kLeft, {0, 0, 0});
  d.WriteForce(Side::kLeft, {100, 0, 0});
  HandSample s;
  d.Read(Side::kLeft, 1, s);
  CHECK(s.force[0] == Approx(7.0));
  d.WriteForce(Side::kLeft, {std::nan(""), 0, 0});
  d.Read(Side::kLeft, 2, s);
  CHECK(s.force[0] == 0.0);
}

TEST_CASE("a late read integrates in bounded sub-steps and stays stable") {
  SimDevice d(SimDeviceConfig{}, OperatorConfig{});
  d.Place(Side::kRight, {0, 0, 0});
  d.SetOperatorTarget(Side::kRight, {0.05, 0, 0});
  HandSample s;
  d.Read(Side::kRight, 1, s);
  d.Read(Side::kRight, 1 + 40 * kMs, s);  // a 40 ms stall
  CHECK(std::isfinite(s.position[0]));
  CHECK(std::abs(s.position[0]) < 0.1);
}
