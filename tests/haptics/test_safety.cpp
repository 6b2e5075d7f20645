#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "haptel/config/error.hpp"
#include "haptel/haptics/safety.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;
SafetyConfig Config() {
  SafetyConfig c;
  c.wrist_force_limit = 7.0;
  c.finger_force_limit = 10.0;
  c.max_force_rate = 1000.0;  // 1 N per ms
  c.soft_start_s = 0.1;
  c.setpoint_timeout_s = 0.02;
  c.fade_s = 0.03;
  return c;
}
/// Applies a constant request every ms from t0 for `ms` ticks; returns the last output.
Vec3d Hold(ForceSafety& s, int64_t& t, int ms, const Vec3d& request, bool fresh = true) {
  Vec3d out{};
  std::array<double, kFingers> fingers{};
  const int64_t stamp = t;
  for (int i = 0; i < ms; ++i) {
    t += kMs;
    fingers = {};
    s.Apply(t, fresh ? t : stamp, request, {}, out, fingers);
  }
  return out;
}
}  // namespace

TEST_CASE("nothing reaches the device before connect") {
  ForceSafety s(Config(), 7.0, 10.0);
  Vec3d out{1, 1, 1};
  std::array<double, kFingers> fingers{1, 1, 1, 1, 1};
  s.Apply(1 * kMs, 1 * kMs, {3, 0, 0}, {}, out, fingers);
  CHECK(out[0] == 0.0);
  CHECK(fingers[0] == 0.0);
}

TEST_CASE("soft start ramps forces in over soft_start_s after connect") {
  ForceSafety s(Config(), 7.0, 10.0);
  int64_t t = 0;
  s.OnConnect(t);
  const Vec3d half = Hold(s, t, 50, {4, 0, 0});
  CHECK(half[0] == Approx(2.0).margin(0.05));  // 50 ms of 100 ms
  const Vec3d full = Hold(s, t, 60, {4, 0, 0});
  CHECK(full[0] == Approx(4.0));
}

TEST_CASE("the wrist force is clamped to the smaller of configured and device limits") {
  ForceSafety s(Config(), 5.0, 10.0);
  CHECK(s.wrist_limit() == 5.0);
  int64_t t = 0;
  s.OnConnect(t);
  const Vec3d out = Hold(s, t, 300, {30, 40, 0});
  CHECK(std::hypot(out[0], out[1]) == Approx(5.0));
  CHECK(out[0] / out[1] == Approx(0.75));  // direction kept
  CHECK(s.counters().clamped > 0);
}

TEST_CASE("finger forces only pull and are clamped per finger") {
  ForceSafety s(Config(), 7.0, 10.0);
  s.OnConnect(0);
  Vec3d out{};
  std::array<double, kFingers> fingers{};
  for (int i = 1; i <= 300; ++i) {
    fingers = {-3, 4, 50, 0, 2};
    s.Apply(i * kMs, i * kMs, {}, {}, out, fingers);
  }
  CHECK(fingers[0] == 0.0);
  CHECK(fingers[1] == Approx(4.0));
  CHECK(fingers[2] == Approx(10.0));
  CHECK(fingers[4] == Approx(2.0));
}

TEST_CASE("the rate limit bounds each change per tick") {
  SafetyConfig c = Config();
  c.soft_start_s = 0.0;
  ForceSafety s(c, 7.0, 10.0);
  int64_t t = 0;
  s.OnConnect(t);
  const Vec3d first = Hold(s, t, 1, {5, -4, 0});
  CHECK(first[0] == Approx(1.0));  // 1000 N/s over 1 ms
  CHECK(first[1] == Approx(-1.0));
  const Vec3d later = Hold(s, t, 4, {5, -4, 0});
  CHECK(later[0] == Approx(5.0));
  CHECK(later[1] == Approx(-4.0));
  CHECK(s.counters().rate_limited > 0);
}

TEST_CASE("NaN or Inf requests become zero and are counted") {
  SafetyConfig c = Config();
  c.soft_start_s = 0.0;
  c.max_force_rate = 1e6;  // the most SafetyConfig allows: 1000 N per 1 ms tick
  ForceSafety s(c, 7.0, 10.0);
  s.OnConnect(0);
  Vec3d out{};
  std::array<double, kFingers> fingers{std::numeric_limits<double>::infinity(), 0, 0, 0, 0};
  s.Apply(1 * kMs, 1 * kMs, {std::numeric_limits<double>::quiet_NaN(), 2, 0}, {}, out, fingers);
  CHECK(out[0] == 0.0);
  CHECK(out[1] == 0.0);  // the whole vector: a NaN component makes the direction meaningless
  CHECK(fingers[0] == 0.0);
  CHECK(s.counters().non_finite == 1);
}

TEST_CASE("stale set-points fade to zero within timeout + fade; local forces stay") {
  SafetyConfig c = Config();
  c.soft_start_s = 0.0;
  c.max_force_rate = 1e6;  // the most SafetyConfig allows: 1000 N per 1 ms tick
  ForceSafety s(c, 7.0, 10.0);
  s.OnConnect(0);
  const int64_t stamp = 1 * kMs;
  Vec3d out{};
  std::array<double, kFingers> fingers{};
  auto at = [&](int64_t t) {
    fingers = {5, 0, 0, 0, 0};
    s.Apply(t, stamp, {4, 0, 0}, {0, 0, 2}, out, fingers);
    return out;
  };
  CHECK(at(stamp + 20 * kMs)[0] == Approx(4.0));  // within the timeout
  CHECK(at(stamp + 35 * kMs)[0] == Approx(2.0));  // half way through the fade
  CHECK(fingers[0] == Approx(2.5));
  CHECK(at(stamp + 50 * kMs)[0] == Approx(0.0));  // gone at 50 ms
  CHECK(out[2] == Approx(2.0));                   // gravity compensation is local: kept
  CHECK(at(stamp + 500 * kMs)[0] == 0.0);
  CHECK(s.counters().stale_ticks >= 3);
}

TEST_CASE("a set-point never written gives no force") {
  ForceSafety s(Config(), 7.0, 10.0);
  CHECK(s.FadeGain(10 * kMs, 0) == 0.0);
  // ... and is not counted as stale: every session starts that way.
  s.OnConnect(0);
  Vec3d out{};
  std::array<double, kFingers> fingers{};
  for (int i = 1; i <= 5; ++i) s.Apply(i * kMs, 0, {4, 0, 0}, {}, out, fingers);
  CHECK(out[0] == 0.0);
  CHECK(s.counters().stale_ticks == 0);
}

TEST_CASE("on loss the output is zero at once, bypassing the rate limit") {
  SafetyConfig c = Config();
  c.soft_start_s = 0.0;
  ForceSafety s(c, 7.0, 10.0);
  int64_t t = 0;
  s.OnConnect(t);
  REQUIRE(Hold(s, t, 10, {5, 0, 0})[0] == Approx(5.0));
  s.OnLost();
  Vec3d out{};
  std::array<double, kFingers> fingers{};
  s.Apply(t + kMs, t + kMs, {5, 0, 0}, {}, out, fingers);
  CHECK(out[0] == 0.0);
  s.OnConnect(t + 2 * kMs);
  s.Apply(t + 3 * kMs, t + 3 * kMs, {5, 0, 0}, {}, out, fingers);
  CHECK(out[0] <= 1.0 + 1e-9);  // ramps from zero again
}

TEST_CASE("force safety refuses a config SafetyConfig::ValidateOrThrow refuses") {
  SafetyConfig c = Config();
  c.setpoint_timeout_s = 0.04;  // 40 ms + 30 ms of fade: forces not gone 50 ms after a stall
  CHECK_THROWS_WITH(ForceSafety(c, 7.0, 10.0),
                    Catch::Contains("fade_s: expected setpoint_timeout_s + fade_s <= 0.05"));
  c = Config();
  c.wrist_force_limit = std::numeric_limits<double>::infinity();
  CHECK_THROWS_AS(ForceSafety(c, 7.0, 10.0), ConfigFieldError);
}
