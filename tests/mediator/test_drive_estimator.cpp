// What the operator side learns of the robot it drives (drive_estimator.hpp):
// known gains and effective track width recovered from states alone.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "haptel/mediator/drive_estimator.hpp"
#include "haptel/models/tread_drive.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

/// The vehicle file's drive (the shipped numbers: 8 levels, 0.3 m/s, 0.16 m).
TreadDriveConfig Nominal() { return TreadDriveConfig{}; }

/// A robot that is not its file: weaker left tread, stronger right, and a
/// skid that turns it as a 1.4× wider one would.
TreadDriveConfig Truth() {
  TreadDriveConfig truth = Nominal();
  truth.left_gain = 0.88;
  truth.right_gain = 1.07;
  truth.track_width = 1.4 * Nominal().track_width;
  return truth;
}

/// Levels a driver gives: straight, both turns, reversing, a stop; changed
/// every 0.5 s.
std::pair<int, int> Levels(double t) {
  static constexpr std::pair<int, int> kSequence[] = {{6, 6}, {3, 8},  {8, 2},   {0, 0},
                                                      {5, 7}, {-4, 4}, {-6, -6}, {7, 5}};
  return kSequence[static_cast<size_t>(t / 0.5) % std::size(kSequence)];
}

/// The robot (the tread model with the truth's numbers, 1 ms steps) reporting
/// its speed and yaw rate every 20 ms, with Gaussian noise of `speed_sd`
/// and `yaw_sd`; levels change only just after a state.
struct SyntheticDrive {
  TreadDriveConfig truth = Truth();
  double speed_sd = 0.0;
  double yaw_sd = 0.0;
  std::mt19937 random{7};
  models::TreadState treads;
  double t = 0.0;
  /// The floor's grip at time t (1: everywhere but a patch): on a patch the
  /// body turns by only this share of what the treads do. The gyro sees the
  /// body's turn; the encoders still the treads' speed (sim_robot.cpp).
  double (*traction)(double t) = [](double) { return 1.0; };

  DriveObservation Next() {
    const auto [left, right] = Levels(t);
    double yaw_rate = 0.0;
    for (int i = 0; i < 20; ++i) {
      yaw_rate = models::StepTreads(truth, models::LevelSpeed(truth, left),
                                    models::LevelSpeed(truth, right), 0.001, treads);
    }
    t += 0.02;
    std::normal_distribution<double> speed_noise(0.0, speed_sd > 0 ? speed_sd : 1.0);
    std::normal_distribution<double> yaw_noise(0.0, yaw_sd > 0 ? yaw_sd : 1.0);
    DriveObservation o;
    o.stamp_s = t;
    o.speed = 0.5 * (treads.v_left + treads.v_right) + (speed_sd > 0 ? speed_noise(random) : 0.0);
    o.yaw_rate = traction(t) * yaw_rate + (yaw_sd > 0 ? yaw_noise(random) : 0.0);
    o.applied_left = left;
    o.applied_right = right;
    return o;
  }
};

}  // namespace

TEST_CASE("Gains and track width from three states worked by hand") {
  // No motor lag: each tread runs at gain × level × 0.3/8 m/s at once.
  // Truth: g_l 0.9, g_r 1.1, B 0.2 m.
  //   levels 4, 4: treads 0.135, 0.165 m/s → speed 0.15,   yaw (0.165 − 0.135)/0.2 = 0.15
  //   levels 2, 6: treads 0.0675, 0.2475   → speed 0.1575, yaw 0.18/0.2 = 0.9
  //   levels 6, 2: treads 0.2025, 0.0825   → speed 0.1425, yaw −0.12/0.2 = −0.6
  TreadDriveConfig nominal = Nominal();
  nominal.motor_time_constant = 0.0;
  DriveEstimator estimator(nominal);
  struct Row {
    int left, right;
    double speed, yaw_rate;
  };
  const Row rows[] = {{4, 4, 0.15, 0.15}, {2, 6, 0.1575, 0.9}, {6, 2, 0.1425, -0.6}};
  double t = 0.0;
  estimator.Observe({t, 0.0, 0.0, 0, 0, false});  // the first state seeds the lag
  for (int i = 0; i < 30; ++i) {
    const Row& r = rows[i % 3];
    t += 0.02;
    estimator.Observe({t, r.speed, r.yaw_rate, r.left, r.right, false});
  }
  REQUIRE(estimator.gains_known());
  REQUIRE(estimator.width_known());
  CHECK(estimator.left_gain() == Approx(0.9).epsilon(1e-9));
  CHECK(estimator.right_gain() == Approx(1.1).epsilon(1e-9));
  CHECK(estimator.track_width() == Approx(0.2).epsilon(1e-9));
  const TreadDriveConfig learnt = estimator.Drive();
  CHECK(learnt.left_gain == Approx(0.9).epsilon(1e-9));
  CHECK(learnt.track_width == Approx(0.2).epsilon(1e-9));
  CHECK(learnt.max_speed == nominal.max_speed);  // what it does not estimate is the file's
}

TEST_CASE("A synthetic drive without noise: the estimate equals the truth") {
  SyntheticDrive drive;
  DriveEstimator estimator(Nominal());
  estimator.Observe({0.0, 0.0, 0.0, 0, 0, false});  // at rest at the start
  while (drive.t < 20.0) estimator.Observe(drive.Next());
  REQUIRE(estimator.width_known());
  CHECK(std::abs(estimator.left_gain() - 0.88) < 1e-6);
  CHECK(std::abs(estimator.right_gain() - 1.07) < 1e-6);
  CHECK(std::abs(estimator.track_width() - 1.4 * 0.16) < 1e-6);
  // Known within the first turns: a second of driving.
  CHECK(estimator.gains_known_at_s() < 1.5);
  CHECK(estimator.width_known_at_s() < 2.0);
  CHECK(estimator.resets() == 0);
}

TEST_CASE("A synthetic drive with odometry noise: within 2 % in 10 s") {
  SyntheticDrive drive;
  drive.speed_sd = 0.01;  // m/s: a third of a level
  drive.yaw_sd = 0.05;    // rad/s
  DriveEstimator estimator(Nominal());
  while (drive.t < 10.0) estimator.Observe(drive.Next());
  CHECK(estimator.width_known());
  CHECK(estimator.width_known_at_s() < 6.0);
  CAPTURE(estimator.left_gain(), estimator.right_gain(), estimator.track_width());
  CHECK(estimator.left_gain() == Approx(0.88).epsilon(0.02));
  CHECK(estimator.right_gain() == Approx(1.07).epsilon(0.02));
  CHECK(estimator.track_width() == Approx(1.4 * 0.16).epsilon(0.02));
  // And it holds there (forgetting keeps ~10 s of memory, no more).
  while (drive.t < 30.0) estimator.Observe(drive.Next());
  CHECK(estimator.left_gain() == Approx(0.88).epsilon(0.02));
  CHECK(estimator.track_width() == Approx(1.4 * 0.16).epsilon(0.02));
  CHECK(estimator.resets() == 0);
}

TEST_CASE("What the states do not show moves nothing") {
  SECTION("driven straight, the track width is not seen") {
    DriveEstimator estimator(Nominal());
    double t = 0.0;
    for (int i = 0; i < 500; ++i, t += 0.02) {
      // Both treads at level 6 and the truth's gains: a slow curve, no turn commanded.
      const double vl = 0.88 * 6 * 0.3 / 8, vr = 1.07 * 6 * 0.3 / 8;
      estimator.Observe({t, 0.5 * (vl + vr), (vr - vl) / 0.224, 6, 6, false});
    }
    CHECK(estimator.width_updates() == 0);
    CHECK_FALSE(estimator.width_known());
    CHECK(estimator.track_width() == Nominal().track_width);
  }
  SECTION("a pressed bumper, or a robot at rest, teaches nothing") {
    DriveEstimator estimator(Nominal());
    double t = 0.0;
    for (int i = 0; i < 200; ++i, t += 0.02) estimator.Observe({t, 0.0, 0.0, 8, 8, true});
    for (int i = 0; i < 200; ++i, t += 0.02) estimator.Observe({t, 0.0, 0.0, 0, 0, false});
    CHECK(estimator.gain_updates() == 0);
    CHECK(estimator.left_gain() == Nominal().left_gain);
    CHECK(estimator.right_gain() == Nominal().right_gain);
  }
}

TEST_CASE("A robot that changes (its battery sags by a fifth) is followed") {
  SyntheticDrive drive;
  drive.speed_sd = 0.005;
  drive.yaw_sd = 0.02;
  DriveEstimator estimator(Nominal());
  while (drive.t < 10.0) estimator.Observe(drive.Next());
  REQUIRE(estimator.gains_known());
  drive.truth.left_gain *= 0.8;
  drive.truth.right_gain *= 0.8;
  while (drive.t < 15.0) estimator.Observe(drive.Next());
  // The residuals stay out: the covariance is reset and the gains re-learnt
  // in seconds, not after the 10 s memory.
  CHECK(estimator.resets() >= 1);
  CHECK(estimator.left_gain() == Approx(0.8 * 0.88).epsilon(0.03));
  CHECK(estimator.right_gain() == Approx(0.8 * 1.07).epsilon(0.03));
  CHECK(estimator.track_width() == Approx(1.4 * 0.16).epsilon(0.03));
}

TEST_CASE("Floor patches of less grip do not carry the track width away") {
  // harsh's patches: traction 0.8, 0.25 m across, crossed in 2 s while
  // turning; here one every 5 s from 10 s on (40 % of the time on a patch:
  // more than any shipped track holds).
  SyntheticDrive drive;
  drive.speed_sd = 0.005;
  drive.yaw_sd = 0.02;
  drive.traction = [](double t) { return t > 10.0 && std::fmod(t, 10.0) < 2.0 ? 0.8 : 1.0; };
  DriveEstimator estimator(Nominal());
  while (drive.t < 10.0) estimator.Observe(drive.Next());
  REQUIRE(estimator.width_known());
  const double truth = 1.4 * Nominal().track_width;
  double worst = 0.0;
  while (drive.t < 40.0) {
    estimator.Observe(drive.Next());
    worst = std::max(worst, std::abs(estimator.track_width() / truth - 1.0));
  }
  CAPTURE(worst, estimator.track_width(), estimator.resets());
  // Each patch is a burst of yaw residuals of one sign, not a new robot: its
  // pull is bounded (Huber) and it resets nothing. Unguarded, the width
  // followed each patch to 1/0.8 of the truth.
  CHECK(worst < 0.05);
  CHECK(estimator.left_gain() == Approx(0.88).epsilon(0.02));
  CHECK(estimator.right_gain() == Approx(1.07).epsilon(0.02));
}

TEST_CASE(
    "The mean gain first, from the speed; the split between the treads once a turn shows it") {
  // No motor lag. Truth: g_l 0.9, g_r 1.1, B 0.2 m; the file says 1.0 / 0.95.
  //   levels 4, 4 (straight): treads 0.135, 0.165 m/s → speed 0.15, yaw 0.15
  //   levels 2, 6 (a turn):   treads 0.0675, 0.2475  → speed 0.1575, yaw 0.9
  // Straight, the speed gives the mean gain 0.15 / 0.15 = 1.0, but not how it
  // splits (each tread's level is the same): the file's split stands,
  // g_l = 2 × 1.0 / (1 + 0.95) = 1.025641, g_r = 2 × 1.0 × 0.95 / 1.95 = 0.974359.
  TreadDriveConfig nominal = Nominal();
  nominal.motor_time_constant = 0.0;
  DriveEstimator estimator(nominal);
  double t = 0.0;
  estimator.Observe({t, 0.0, 0.0, 0, 0, false});
  for (int i = 0; i < 20; ++i) {
    t += 0.02;
    estimator.Observe({t, 0.15, 0.15, 4, 4, false});
  }
  REQUIRE(estimator.gains_known());
  CHECK_FALSE(estimator.ratio_known());
  CHECK_FALSE(estimator.width_known());
  CHECK(estimator.left_gain() == Approx(2.0 / 1.95).epsilon(1e-9));
  CHECK(estimator.right_gain() == Approx(1.9 / 1.95).epsilon(1e-9));
  CHECK(estimator.track_width() == nominal.track_width);
  // One turn: with a = g / B, the yaw rate's two lines are
  //   straight: −0.15 a_l + 0.15 a_r = 0.15  → a_r − a_l = 1
  //   turning:  −0.075 a_l + 0.225 a_r = 0.9 → a_l = 4.5, a_r = 5.5
  // so the split is 5.5 / 4.5 and the width 2 × 1.0 / (4.5 + 5.5) = 0.2 m.
  for (int i = 0; i < 10; ++i) {
    t += 0.02;
    estimator.Observe({t, 0.1575, 0.9, 2, 6, false});
  }
  REQUIRE(estimator.ratio_known());
  REQUIRE(estimator.width_known());
  CHECK(estimator.gain_ratio() == Approx(1.1 / 0.9).epsilon(1e-9));
  CHECK(estimator.left_gain() == Approx(0.9).epsilon(1e-9));
  CHECK(estimator.right_gain() == Approx(1.1).epsilon(1e-9));
  CHECK(estimator.track_width() == Approx(0.2).epsilon(1e-9));
}

TEST_CASE("A state sampled before the one ahead of it is left out, not taken as a gap") {
  // harsh's state jitter sends a measurement up to 30 ms old: one state in
  // eleven is older than the one before. Taken as a gap, each stopped the
  // learning for 10 motor time constants (0.8 s), and on harsh for good.
  SyntheticDrive drive;
  DriveEstimator estimator(Nominal());
  estimator.Observe({0.0, 0.0, 0.0, 0, 0, false});
  DriveObservation previous{};
  int late = 0;
  for (int i = 1; drive.t < 20.0; ++i) {
    const DriveObservation now = drive.Next();
    estimator.Observe(now);
    if (i % 11 == 0) {
      estimator.Observe(previous);  // the older one again, after the newer
      ++late;
    }
    previous = now;
  }
  REQUIRE(late > 80);
  REQUIRE(estimator.width_known());
  CHECK(estimator.gains_known_at_s() < 1.5);
  CHECK(estimator.width_known_at_s() < 2.0);
  CHECK(std::abs(estimator.left_gain() - 0.88) < 1e-6);
  CHECK(std::abs(estimator.right_gain() - 1.07) < 1e-6);
  CHECK(std::abs(estimator.track_width() - 1.4 * 0.16) < 1e-6);
}
