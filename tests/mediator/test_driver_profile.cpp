// The simulated driver's profile (DriverProfile) in AutoOperator, one
// mechanism at a time: each is inert for the ideal driver and produces the
// effect its study file comment names (config/studies/grand-prix-synthetic.yaml).
#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/mediator/auto_operator.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {

const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}

/// An interface whose traits the test chooses: a grip to grasp in the left
/// hand (or free hands), a speedometer, controls that stay put.
struct Controls final : interfaces::MediatorInterface {
  bool grip = true;
  bool speedometer = false;
  bool stay_put = false;
  std::string name() const override { return "controls"; }
  TreadCommand Update(double, const interfaces::VehicleFeedback&, haptics::Hal&) override {
    return {};
  }
  interfaces::HandTargets HandTargetsFor(const interfaces::MotionIntent& intent) const override {
    interfaces::HandGoal g;
    g.position = {0.1 + 0.05 * intent.forward, 0.05 * intent.turn, 0.0};
    g.glove.fill(1.0);
    if (grip) g.approach = {0.0, 0.0, 0.04};
    interfaces::HandTargets t;
    t[haptics::Index(haptics::Side::kLeft)] = g;
    return t;
  }
  bool NeedsPhysics() const override { return grip; }
  bool ShowsSpeed() const override { return speedometer; }
  bool ControlsStayPut() const override { return stay_put; }
};

OperatorConfig Quick() {
  OperatorConfig c;
  c.reaction_delay_s = 0.0;
  c.grasp_reach_s = 0.1;
  c.grasp_close_s = 0.1;
  c.arm_time_constant_s = 0.05;
  return c;
}

/// The forward command the driver gives for a full-forward intent, once
/// holding `controls` (the first Act starts the grasp).
double Cruise(const DriverProfile& profile, const Controls& controls, int experience = 100) {
  AutoOperator op(ShortTrack(), Quick(), TreadDriveConfig{}, profile, experience);
  op.Act(0.0, controls);
  return op.Express(1.0, {1.0, 0.0}, controls).forward;
}

}  // namespace

TEST_CASE("the ideal driver expresses the intent as decided, on any interface") {
  Controls stay;
  stay.stay_put = true;
  stay.speedometer = true;
  AutoOperator op(ShortTrack(), Quick(), TreadDriveConfig{});
  op.Act(0.0, stay);
  for (double t = 1.0; t < 3.0; t += 0.05) {
    const interfaces::MotionIntent out = op.Express(t, {0.7, -0.2}, stay);
    CHECK(out.forward == Approx(0.7));
    CHECK(out.turn == Approx(-0.2));
  }
  CHECK(op.error_scale() == 1.0);
}

TEST_CASE(
    "errors shrink with the trials done before: 1 + gain at the first, e-folding over "
    "learning_trials") {
  DriverProfile p;
  p.learning_gain = 0.6;
  p.learning_trials = 2.0;
  CHECK(AutoOperator(ShortTrack(), Quick(), TreadDriveConfig{}, p, 0).error_scale() == Approx(1.6));
  CHECK(AutoOperator(ShortTrack(), Quick(), TreadDriveConfig{}, p, 2).error_scale() ==
        Approx(1.0 + 0.6 * std::exp(-1.0)));
  CHECK(AutoOperator(ShortTrack(), Quick(), TreadDriveConfig{}, p, 40).error_scale() ==
        Approx(1.0).margin(1e-6));
  // A speed shortfall scales with it: 0.8 practised is 0.68 at the first trial.
  p.holding_cruise = 0.8;
  Controls grip;
  CHECK(Cruise(p, grip, 0) == Approx(1.0 - 0.2 * 1.6));
  CHECK(Cruise(p, grip, 100) == Approx(0.8));
}

TEST_CASE("holding virtual controls slows the driver; free hands (gesture) do not") {
  DriverProfile p;
  p.holding_cruise = 0.75;
  p.stay_put_cruise = 0.6;
  Controls free_hands;
  free_hands.grip = false;
  Controls returns;  // a grip that springs back to zero (the assisted cockpit)
  Controls stays;    // one that stays where it is left (cockpit, cockpit-HUD)
  stays.stay_put = true;
  CHECK(Cruise(p, free_hands) == Approx(1.0));
  CHECK(Cruise(p, returns) == Approx(0.75));
  CHECK(Cruise(p, stays) == Approx(0.75 * 0.6));
}

TEST_CASE("without a speed cue the driver holds back; a speedometer helps only while read") {
  DriverProfile p;
  p.unsure_cruise = 0.8;
  p.hud_use = 0.25;
  Controls plain;
  plain.grip = false;
  Controls hud = plain;
  hud.speedometer = true;
  CHECK(Cruise(p, plain) == Approx(0.8));
  CHECK(Cruise(p, hud) == Approx(0.25 + 0.75 * 0.8));
  p.hud_use = 1.0;
  CHECK(Cruise(p, hud) == Approx(1.0));
}

TEST_CASE("holding controls delays the driver's reaction") {
  DriverProfile p;
  p.holding_reaction_s = 0.3;
  OperatorConfig c = Quick();
  Controls grip;
  AutoOperator op(ShortTrack(), c, TreadDriveConfig{}, p);
  op.Act(0.0, grip);  // grasping: the reaction delay grows by 0.3 s
  op.Observe(
      {1.0, ShortTrack().PointAt(0.1).x(), ShortTrack().PointAt(0.1).y(), 0.0, false, false});
  CHECK(op.Decide(1.2).forward == 0.0);  // seen 1.0, not yet reacted
  CHECK(op.Decide(1.35).forward > 0.5);
  Controls free_hands;
  free_hands.grip = false;
  AutoOperator quick(ShortTrack(), c, TreadDriveConfig{}, p);
  quick.Act(0.0, free_hands);
  quick.Observe(
      {1.0, ShortTrack().PointAt(0.1).x(), ShortTrack().PointAt(0.1).y(), 0.0, false, false});
  CHECK(quick.Decide(1.01).forward > 0.5);
}

TEST_CASE("the steering wanders with the profile's spread and correlation time") {
  DriverProfile p;
  p.steering_noise = 0.05;
  p.noise_time_s = 0.5;
  p.seed = 7;
  Controls free_hands;
  free_hands.grip = false;
  AutoOperator op(ShortTrack(), Quick(), TreadDriveConfig{}, p, 100);
  op.Act(0.0, free_hands);
  double sum = 0.0, sum2 = 0.0, lag_sum = 0.0, previous = 0.0;
  const double dt = 0.05;
  int n = 0;
  for (double t = 1.0; t < 2001.0; t += dt, ++n) {
    const double turn = op.Express(t, {0.5, 0.0}, free_hands).turn;
    sum += turn;
    sum2 += turn * turn;
    lag_sum += turn * previous;
    previous = turn;
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  CHECK(std::abs(mean) < 0.01);
  CHECK(sd == Approx(0.05).epsilon(0.1));
  // One step's autocorrelation of an Ornstein–Uhlenbeck process: exp(−dt/τ).
  CHECK(lag_sum / n / (sd * sd) == Approx(std::exp(-dt / 0.5)).epsilon(0.05));
}

TEST_CASE(
    "a control slips out of the hand at the profile's rate, the hand opens and grasps again") {
  DriverProfile p;
  p.slip_rate_hz = 0.2;
  p.regrasp_s = 1.0;
  p.seed = 3;
  Controls grip;
  AutoOperator op(ShortTrack(), Quick(), TreadDriveConfig{}, p, 100);
  const int left = haptics::Index(haptics::Side::kLeft);
  op.Observe(
      {0.0, ShortTrack().PointAt(0.1).x(), ShortTrack().PointAt(0.1).y(), 0.0, false, false});
  double open_time = 0.0;
  const double dt = 0.01;
  const double duration = 1000.0;
  for (double t = 0.0; t < duration; t += dt) {
    const interfaces::HandTargets hands = op.Act(t, grip);
    REQUIRE(hands[left]);
    if (op.grasped(t) && hands[left]->glove[0] < 0.5) open_time += dt;
  }
  // A Poisson process of rate 0.2/s while held (held about 1/(1 + 0.2·1) of the time).
  const double expected = 0.2 * duration / (1.0 + 0.2 * 1.0);
  CHECK(op.slips() == Approx(expected).epsilon(0.2));
  // The hand is more than half open for half of each regrasp.
  CHECK(open_time == Approx(op.slips() * 0.5).epsilon(0.1));
  // The ideal driver never slips.
  AutoOperator steady(ShortTrack(), Quick(), TreadDriveConfig{});
  for (double t = 0.0; t < 100.0; t += 0.1) steady.Act(t, grip);
  CHECK(steady.slips() == 0);
}

TEST_CASE("a control that stays put comes back to its centre slowly and misses it") {
  DriverProfile p;
  p.recentre_s = 0.5;
  p.recentre_error = 0.05;
  p.seed = 5;
  Controls stays;
  stays.stay_put = true;
  OperatorConfig c = Quick();
  c.arm_time_constant_s = 0.0;
  AutoOperator op(ShortTrack(), c, TreadDriveConfig{}, p, 100);
  op.Act(0.0, stays);
  // Away from the centre at once...
  CHECK(op.Express(1.0, {0.0, 0.8}, stays).turn == Approx(0.8));
  // ...back towards it with a time constant of 0.5 s.
  const double after = op.Express(1.5, {0.0, 0.0}, stays).turn;
  CHECK(std::abs(after) > 0.2);
  CHECK(std::abs(after) < 0.4);
  double settled = 0.0;
  for (double t = 1.5; t < 6.0; t += 0.05) settled = op.Express(t, {0.0, 0.0}, stays).turn;
  CHECK(std::abs(settled) < 0.2);  // near the centre, not on it (a miss of sd 0.05)
  CHECK(settled != 0.0);
  // A control that springs back: no lag, no miss.
  Controls returns;
  AutoOperator spring(ShortTrack(), c, TreadDriveConfig{}, p, 100);
  spring.Act(0.0, returns);
  spring.Express(1.0, {0.0, 0.8}, returns);
  CHECK(spring.Express(1.5, {0.0, 0.0}, returns).turn == 0.0);
}

TEST_CASE(
    "after a contact the driver aims: no wander and no centre miss for careful_s, then both "
    "return") {
  DriverProfile p;
  p.steering_noise = 0.1;
  p.noise_time_s = 0.5;
  p.recentre_s = 0.2;
  p.recentre_error = 0.05;
  p.seed = 9;
  Controls stays;
  stays.stay_put = true;
  OperatorConfig c = Quick();
  c.arm_time_constant_s = 0.0;
  c.backoff_s = 0.8;
  c.careful_s = 4.0;
  AutoOperator op(ShortTrack(), c, TreadDriveConfig{}, p, 100);
  const Vec2 at = ShortTrack().PointAt(0.1);
  op.Act(0.0, stays);
  // Before any contact a small wanted turn is wandered and snapped to a missed centre.
  double before = 0.0;
  for (double t = 1.0; t < 3.0; t += 0.05)
    before = std::max(before, std::abs(op.Express(t, {0.5, 0.02}, stays).turn - 0.02));
  CHECK(before > 0.02);
  REQUIRE_FALSE(op.careful(3.0));
  // A contact at t = 3: backing off until 3.8, aiming until 7.8.
  Observation o{3.0, at.x(), at.y(), 0.0, true, false};
  op.Observe(o);
  op.Decide(3.0);
  CHECK(op.backing_off(3.5));
  CHECK(op.careful(7.7));
  CHECK_FALSE(op.careful(7.9));
  // Aiming: a small turn is given as wanted once the control has come to it.
  double during = 0.0;
  for (double t = 5.5; t < 7.7; t += 0.05)
    during = std::max(during, std::abs(op.Express(t, {0.5, 0.02}, stays).turn - 0.02));
  CHECK(during < 1e-3);
  // Attention lapses again.
  double after = 0.0;
  for (double t = 7.9; t < 10.0; t += 0.05)
    after = std::max(after, std::abs(op.Express(t, {0.5, 0.02}, stays).turn - 0.02));
  CHECK(after > 0.02);
}
