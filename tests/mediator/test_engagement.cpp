// A hand that lets go stops the vehicle: a held hand is told from an arm
// nobody holds by its tremor (MeasureHandMotion), and the interface is
// engaged only while its hands are held within reach, and again only from
// rest (Engagement).
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

#include "haptel/haptics/sim_device.hpp"
#include "haptel/mediator/engagement.hpp"

using namespace haptel;
using namespace haptel::haptics;
using namespace haptel::mediator;

namespace {

constexpr int64_t kMs = 1'000'000;
constexpr double kEncoder = 60e-6;  // m: the sim device's encoder

/// 1 kHz tracker samples over [0, seconds) of a hand at `at(t)` (m),
/// quantised to the encoder, in the default calibration's units (0.01 m each).
std::vector<TrackerSample> Samples(double seconds, const std::function<Vec3d(double)>& at) {
  std::vector<TrackerSample> out;
  for (int i = 0; i < static_cast<int>(seconds * 1000); ++i) {
    const Vec3d p = at(i * 1e-3);
    TrackerSample s;
    s.t_ns = (i + 1) * kMs;
    for (int k = 0; k < 3; ++k) s.raw[k] = std::round(p[k] / kEncoder) * kEncoder / 0.01;
    out.push_back(s);
  }
  return out;
}

/// A hand held still at `centre`: tremor of `amplitude` (m) at about `hz` on each axis.
std::function<Vec3d(double)> Tremor(double amplitude, double hz, Vec3d centre = {0.01, 0.02, 0}) {
  return [=](double t) {
    Vec3d p = centre;
    for (int k = 0; k < 3; ++k) {
      const double w = 2 * std::numbers::pi * hz * (1.0 + 0.04 * (k - 1));
      p[k] += amplitude * std::sin(w * t + 1.3 * k);
    }
    return p;
  };
}

HandMotion Judge(const std::vector<TrackerSample>& samples) {
  return MeasureHandMotion(samples, ArmCalibration{});
}

/// Publishes `samples` (shifted to start after the HAL's newest) into `hal`'s right arm.
void Publish(Hal& hal, const std::vector<TrackerSample>& samples, int64_t& t_ns) {
  for (const TrackerSample& s : samples) {
    t_ns += kMs;
    WristRaw raw;
    raw.t_ns = t_ns;
    raw.position = s.raw;
    hal.PublishWrist(Side::kRight, raw);
  }
}

/// The gesture interface's rest: the right hand, neutral at the origin.
InterfaceRest GestureRest(bool command_at_rest) {
  InterfaceRest rest;
  rest.hands = {false, true};
  rest.neutral[1] = Vec3d{0, 0, 0};
  rest.command_at_rest = command_at_rest;
  return rest;
}

}  // namespace

TEST_CASE("a hand held still shakes with tremor and is taken for held", "[engagement]") {
  struct Case {
    double amplitude, hz;
  };
  for (const Case c : {Case{0.2e-3, 10.0}, Case{0.1e-3, 8.0}, Case{0.5e-3, 12.0}}) {
    INFO(c.amplitude * 1e3 << " mm at " << c.hz << " Hz");
    const HandMotion m = Judge(Samples(1.0, Tremor(c.amplitude, c.hz)));
    CHECK(m.held);
    CHECK(m.span_s == Approx(HandMotionRule::kWindow_s).margin(0.002));
    CHECK(m.reversals_hz >= 2 * c.hz * 0.8);
    CHECK(m.rms_mps >= HandMotionRule::kMinRms_mps);
  }
  // Not yet half a second of history: too early to tell.
  CHECK_FALSE(Judge(Samples(0.3, Tremor(0.2e-3, 10.0))).held);
}

TEST_CASE("a still arm, or one whose encoder flickers by a count, is not held", "[engagement]") {
  const HandMotion still = Judge(Samples(1.0, [](double) { return Vec3d{0.05, -0.1, -0.2}; }));
  CHECK_FALSE(still.held);
  CHECK(still.rms_mps == 0.0);
  // Resting on an encoder step: each reading one count either side, at random.
  std::mt19937 rng(7);
  std::bernoulli_distribution flip(0.5);
  const HandMotion flicker = Judge(Samples(1.0, [&](double) {
    const double edge = 100.5 * kEncoder;
    return Vec3d{edge + (flip(rng) ? 0.3 : -0.3) * kEncoder, edge, edge};
  }));
  CHECK_FALSE(flicker.held);
  CHECK(flicker.rms_mps < HandMotionRule::kMinRms_mps);
}

TEST_CASE("an arm swinging back to neutral under a field and settling is not held",
          "[engagement]") {
  // Let go 3 cm off neutral under a spring: a damped 2 Hz swing.
  const auto swing = [](double t) {
    return Vec3d{0.03 * std::exp(-t / 0.4) * std::cos(2 * std::numbers::pi * 2.0 * t), 0, 0};
  };
  const std::vector<TrackerSample> samples = Samples(2.0, swing);
  for (size_t end = 500; end <= samples.size(); end += 100) {
    INFO("judged at " << end * 1e-3 << " s");
    const HandMotion m = Judge({samples.begin(), samples.begin() + static_cast<long>(end)});
    CHECK_FALSE(m.held);
    // While it swings it reverses too seldom; settled, it moves too little
    // (its encoder's last steps may flicker often, by little).
    if (end <= 1000) CHECK(m.reversals_hz < HandMotionRule::kMinReversals_hz);
    if (end >= 1500) CHECK(m.rms_mps < HandMotionRule::kMinRms_mps);
  }
}

TEST_CASE("the simulated operator's hand is held; released mid-air it is not within a second",
          "[engagement]") {
  DeviceConfig device;
  OperatorConfig op;  // the default tremor
  SimDevice sim(device, op);
  DeviceCalibration calibration;
  for (int s = 0; s < kSides; ++s) {
    calibration.arms[s].tracker_scale = sim.truth(static_cast<Side>(s)).tracker_scale;
    calibration.arms[s].tracker_offset = sim.truth(static_cast<Side>(s)).tracker_offset;
  }
  Hal hal(calibration);
  const Side side = Side::kRight;
  const Vec3d neutral{0, 0, 0};
  sim.Place(side, {0.02, 0.01, 0.0});
  sim.SetOperatorTarget(side, {0.02, 0.01, 0.0});
  // The gesture's field pulls the hand to neutral (40 N/m, 2 N·s/m).
  int64_t t = kMs;
  std::vector<TrackerSample> history(Hal::kTrackerHistory);
  auto run_for = [&](double seconds, const std::function<void(double)>& each_10ms) {
    for (int i = 0; i < static_cast<int>(seconds * 1000); ++i) {
      t += kMs;
      WristRaw raw;
      REQUIRE(sim.ReadWrist(side, t, raw) == DeviceStatus::kOk);
      hal.PublishWrist(side, raw);
      const Vec3d x = sim.TruePosition(side);
      const Vec3d v = sim.TrueVelocity(side);
      Vec3d command{};
      for (int k = 0; k < 3; ++k) {
        command[k] = (-40.0 * (x[k] - neutral[k]) - 2.0 * v[k]) / sim.truth(side).force_slope[k];
      }
      sim.WriteWristForce(side, command);
      if (i % 10 == 9) each_10ms(i * 1e-3);
    }
  };
  auto judge = [&] {
    const size_t n = hal.TrackerHistory(side, history);
    return MeasureHandMotion(std::span(history.data(), n), calibration.arms[1]);
  };
  int held_judged = 0, held = 0;
  run_for(1.0, [&](double since) {
    if (since < HandMotionRule::kWindow_s) return;
    ++held_judged;
    held += judge().held ? 1 : 0;
  });
  CHECK(held == held_judged);
  CHECK(judge().reversals_hz >= 16.0);  // ~10 Hz: 20 reversals a second

  sim.Release(side);
  double last_held_s = -1.0;
  run_for(3.0, [&](double since) {
    if (judge().held) last_held_s = since;
  });
  CHECK(last_held_s < 1.0);
  // It came to rest under the field, below neutral where the exoskeleton's weight takes it.
  CHECK(std::abs(sim.TrueVelocity(side)[0]) < 1e-3);
}

TEST_CASE("a simulated arm held by an operator without tremor is not taken for held",
          "[engagement]") {
  OperatorConfig op;
  op.tremor_amplitude = 0.0;
  SimDevice sim(DeviceConfig{}, op);
  Hal hal;  // raw units are all that is judged: any calibration tells still from moving
  sim.Place(Side::kRight, {0.02, 0.01, 0.0});
  int64_t t = kMs;
  for (int i = 0; i < 1000; ++i) {
    t += kMs;
    WristRaw raw;
    sim.ReadWrist(Side::kRight, t, raw);
    hal.PublishWrist(Side::kRight, raw);
  }
  std::vector<TrackerSample> history(Hal::kTrackerHistory);
  const size_t n = hal.TrackerHistory(Side::kRight, history);
  CHECK_FALSE(MeasureHandMotion(std::span(history.data(), n), ArmCalibration{}).held);
}

TEST_CASE("the interface engages with held hands at rest, and again only from rest",
          "[engagement]") {
  Hal hal;
  int64_t t = 0;
  Engagement engagement;
  CHECK_FALSE(engagement.engaged());
  Publish(hal, Samples(0.6, Tremor(0.2e-3, 10.0)), t);

  SECTION("a hand grabbed away from rest does not lurch the vehicle") {
    CHECK_FALSE(engagement.Update(hal, GestureRest(false)));
    CHECK(engagement.why() == Disengaged::kNotAtNeutral);
    CHECK(engagement.Update(hal, GestureRest(true)));
    // Engaged, the command may leave rest: that is driving.
    CHECK(engagement.Update(hal, GestureRest(false)));
  }
  SECTION("the device's word: released disengages at once, whatever the motion") {
    REQUIRE(engagement.Update(hal, GestureRest(true)));
    hal.PublishPresence(Side::kRight, HandPresence::kReleased);
    CHECK_FALSE(engagement.Update(hal, GestureRest(false)));
    CHECK(engagement.why() == Disengaged::kReleased);
    CHECK(std::string(engagement.Line()).find("hold the button") != std::string::npos);
    // Held again (its button down) with the hand off rest: it waits for rest.
    hal.PublishPresence(Side::kRight, HandPresence::kHeld);
    CHECK_FALSE(engagement.Update(hal, GestureRest(false)));
    CHECK(engagement.why() == Disengaged::kNotAtNeutral);
    CHECK(engagement.Update(hal, GestureRest(true)));
  }
  SECTION("a hand out of reach of the neutral point disengages") {
    REQUIRE(engagement.Update(hal, GestureRest(true)));
    hal.PublishPresence(Side::kRight, HandPresence::kHeld);  // no tremor needed
    const Vec3d far{Engagement::kReach_m + 0.01, 0, 0};
    Publish(hal, Samples(0.01, [&](double) { return far; }), t);
    CHECK_FALSE(engagement.Update(hal, GestureRest(false)));
    CHECK(engagement.why() == Disengaged::kOutOfReach);
    Publish(hal, Samples(0.01, [](double) { return Vec3d{0.01, 0, 0}; }), t);
    CHECK(engagement.Update(hal, GestureRest(true)));
  }
  SECTION("an arm that stops shaking is let go") {
    REQUIRE(engagement.Update(hal, GestureRest(true)));
    Publish(hal, Samples(0.6, [](double) { return Vec3d{0.01, 0.02, 0}; }), t);
    CHECK_FALSE(engagement.Update(hal, GestureRest(true)));
    CHECK(engagement.why() == Disengaged::kNoHand);
    CHECK_FALSE(engagement.motion(Side::kRight).held);
  }
  SECTION("a hand the interface does not use is not asked for") {
    InterfaceRest left_only;
    left_only.hands = {true, false};
    CHECK_FALSE(engagement.Update(hal, left_only));  // the left arm never moved
    InterfaceRest keys;                              // keys: hold-to-drive, no hands
    hal.PublishPresence(Side::kRight, HandPresence::kReleased);
    CHECK(engagement.Update(hal, keys));
  }
}

TEST_CASE("a command is at rest within 5 % on every channel that moves the vehicle",
          "[engagement]") {
  CHECK(AtRest(TreadCommand{0.04, -0.05}));
  CHECK_FALSE(AtRest(TreadCommand{0.0, 0.06}));
  BlimpCommand blimp;
  blimp.camera_pan = 1.0;  // looking around moves nothing
  CHECK(AtRest(blimp));
  blimp.power = 0.2;
  CHECK_FALSE(AtRest(blimp));
}
