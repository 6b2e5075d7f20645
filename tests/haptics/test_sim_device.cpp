#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/haptics/sim_device.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;

/// Runs the device for `seconds` at 1 kHz with a constant force command.
WristRaw RunFor(SimDevice& d, Side side, int64_t& t, double seconds, const Vec3d& command) {
  WristRaw raw;
  const int steps = static_cast<int>(seconds * 1000);
  for (int i = 0; i < steps; ++i) {
    t += kMs;
    REQUIRE(d.ReadWrist(side, t, raw) == DeviceStatus::kOk);
    d.WriteWristForce(side, command);
  }
  return raw;
}
DeviceConfig NoGravity() {
  DeviceConfig c;
  c.sim.exo_unbalanced_mass = 0.0;
  c.sim.coulomb_friction = 0.0;
  return c;
}
}  // namespace

TEST_CASE("the tracker reports in device units through the hidden calibration") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  const Vec3d p{0.05, -0.02, 0.03};
  d.Place(Side::kRight, p);
  WristRaw raw;
  d.ReadWrist(Side::kRight, 1, raw);
  const SimArmTruth& t = d.truth(Side::kRight);
  for (int i = 0; i < 3; ++i) {
    CHECK(t.tracker_scale[i] == Approx(0.01).epsilon(0.06));
    const double metres = t.tracker_scale[i] * raw.position[i] + t.tracker_offset[i];
    CHECK(metres ==
          Approx(p[i]).margin(d.config().encoder_resolution));  // quantised to the encoder
  }
}

TEST_CASE("the simulated operator moves the hand to the target") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  d.Place(Side::kRight, {0, 0, 0});
  d.SetOperatorTarget(Side::kRight, {0.05, -0.02, 0});
  int64_t t = 1;
  RunFor(d, Side::kRight, t, 3.0, {0, 0, 0});
  const Vec3d p = d.TruePosition(Side::kRight);
  CHECK(p[0] == Approx(0.05).margin(0.002));
  CHECK(p[1] == Approx(-0.02).margin(0.002));
  CHECK(p[2] == Approx(0.0).margin(0.003));  // holds the exoskeleton's weight
}

TEST_CASE(
    "the operator pushes harder against a steady pull, but a strong force holds the hand back") {
  OperatorConfig op;
  auto error_under = [&](double pull) {
    SimDevice d(NoGravity(), op);
    d.Place(Side::kRight, {0, 0, 0});
    d.SetOperatorTarget(Side::kRight, {0.05, 0, 0});
    int64_t t = 1;
    const double slope = d.truth(Side::kRight).force_slope[0];
    RunFor(d, Side::kRight, t, 4.0, {-pull / slope, 0, 0});
    return 0.05 - d.TruePosition(Side::kRight)[0];
  };
  const double small = error_under(2.0);
  CHECK(std::abs(small) < 0.003);
  const double large = error_under(7.0);
  CHECK(large > 0.005);
  CHECK(large > 3 * std::abs(small));
}

TEST_CASE(
    "a released arm sinks under the unbalanced exoskeleton weight; friction holds a balanced one") {
  DeviceConfig c;
  SimDevice d(c, OperatorConfig{});
  d.Place(Side::kLeft, {0.1, 0, 0.1});
  d.Release(Side::kLeft);
  int64_t t = 1;
  RunFor(d, Side::kLeft, t, 0.3, {0, 0, 0});
  CHECK(d.TruePosition(Side::kLeft)[2] < 0.1 - 0.01);
  // Balanced to within the friction: stays put.
  SimDevice e(c, OperatorConfig{});
  const Vec3d p{0.1, 0, 0.1};
  e.Place(Side::kLeft, p);
  e.Release(Side::kLeft);
  const double weight = e.UnbalancedMass(p) * SimDevice::kGravity;
  const double slope = e.truth(Side::kLeft).force_slope[2];
  int64_t t2 = 1;
  RunFor(e, Side::kLeft, t2, 1.0, {0, 0, (weight + 0.5 * c.sim.coulomb_friction) / slope});
  CHECK(e.TruePosition(Side::kLeft)[2] == Approx(0.1).margin(1e-6));
}

TEST_CASE("the unbalanced mass varies with position and peaks at the configured worst case") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  const auto& c = d.config();
  double worst = 0.0;
  double least = 1e9;
  for (double x = c.workspace_min[0]; x <= c.workspace_max[0]; x += 0.05)
    for (double y = c.workspace_min[1]; y <= c.workspace_max[1]; y += 0.05)
      for (double z = c.workspace_min[2]; z <= c.workspace_max[2]; z += 0.05) {
        worst = std::max(worst, d.UnbalancedMass({x, y, z}));
        least = std::min(least, d.UnbalancedMass({x, y, z}));
      }
  CHECK(worst <= c.exo_unbalanced_mass + 1e-9);
  CHECK(worst > 0.9 * c.exo_unbalanced_mass);
  CHECK(least < 0.5 * worst);
}

TEST_CASE("the workspace has hard stops") {
  SimDevice d(NoGravity(), OperatorConfig{});
  d.Place(Side::kRight, {0, 0, 0});
  d.SetOperatorTarget(Side::kRight, {1.0, 0, 0});  // far outside
  int64_t t = 1;
  RunFor(d, Side::kRight, t, 3.0, {0, 0, 0});
  CHECK(d.TruePosition(Side::kRight)[0] == Approx(d.config().workspace_max[0]));
}

TEST_CASE("the device saturates commanded forces at its limit and ignores non-finite ones") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  const Vec3d f = d.MeasureForce(Side::kLeft, {100, 0, 0});
  CHECK(f[0] == Approx(d.config().force_limit));
  const Vec3d bad = d.MeasureForce(Side::kLeft, {std::nan(""), 0, 0});
  CHECK(bad[0] == 0.0);
  const Vec3d small = d.MeasureForce(Side::kLeft, {1, 0, 0});
  CHECK(small[0] == Approx(d.truth(Side::kLeft).force_slope[0]));
}

TEST_CASE("the glove reports integer counts through per-sensor gain and offset") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  std::array<double, kGloveJoints> angles{};
  for (int j = 0; j < kGloveJoints; ++j) angles[j] = 0.05 * j;
  d.SetGlovePosture(Side::kRight, angles);
  GloveRaw raw;
  REQUIRE(d.ReadGlove(Side::kRight, 1, raw) == DeviceStatus::kOk);
  const SimArmTruth& t = d.truth(Side::kRight);
  for (int j = 0; j < kGloveJoints; ++j) {
    CHECK(raw.sensors[j] == std::round(raw.sensors[j]));
    CHECK(t.glove_gain[j] * raw.sensors[j] + t.glove_offset[j] ==
          Approx(angles[j]).margin(t.glove_gain[j]));
  }
}

TEST_CASE("a lost side answers kLost on every channel until it recovers") {
  SimDevice d(DeviceConfig{}, OperatorConfig{});
  WristRaw w;
  GloveRaw g;
  d.SetLost(Side::kLeft, true);
  CHECK(d.ReadWrist(Side::kLeft, 1, w) == DeviceStatus::kLost);
  CHECK(d.ReadGlove(Side::kLeft, 1, g) == DeviceStatus::kLost);
  CHECK(d.WriteWristForce(Side::kLeft, {}) == DeviceStatus::kLost);
  CHECK(d.ReadWrist(Side::kRight, 1, w) == DeviceStatus::kOk);
  d.SetLost(Side::kLeft, false);
  CHECK(d.ReadWrist(Side::kLeft, 2, w) == DeviceStatus::kOk);
}

TEST_CASE("the sim device refuses a device or operator config ValidateOrThrow refuses") {
  DeviceConfig c;
  c.sim.arm_mass = 0.0;
  CHECK_THROWS_WITH(SimDevice(c, OperatorConfig{}),
                    Catch::Contains("sim.arm_mass: expected a number in [0.01, 100]"));
  OperatorConfig muscle;
  muscle.muscle_max_force = std::nan("");
  CHECK_THROWS_WITH(SimDevice(DeviceConfig{}, muscle), Catch::Contains("muscle_max_force"));
  CHECK_THROWS_AS(SimDevice(DeviceConfig{}, muscle), ConfigFieldError);
}
