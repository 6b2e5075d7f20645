#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/interfaces/gesture.hpp"
#include "haptel/mediator/auto_operator.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {
const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}
Observation At(double t, const Vec2& p, double heading) {
  return {t, p.x(), p.y(), heading, false, false};
}
}  // namespace

TEST_CASE("the operator waits for its reaction delay before acting") {
  OperatorConfig cfg;
  cfg.reaction_delay_s = 0.15;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  op.Observe(At(1.0, ShortTrack().PointAt(0.0), 0.0));
  const auto early = op.Decide(1.1);
  CHECK(early.forward == 0.0);
  CHECK(early.turn == 0.0);
  const auto late = op.Decide(1.2);
  CHECK(late.forward > 0.5);
}

TEST_CASE("on a straight, aligned with the track, the operator drives straight ahead") {
  AutoOperator op(ShortTrack(), OperatorConfig{}, TreadDriveConfig{});
  const Vec2 p = ShortTrack().PointAt(0.1);  // first straight runs along +x
  op.Observe(At(0.0, p, 0.0));
  const auto intent = op.Decide(1.0);
  CHECK(intent.forward == Approx(OperatorConfig{}.cruise).margin(0.1));
  CHECK(std::abs(intent.turn) < 0.05);
}

TEST_CASE("displaced to the right of the line, the operator steers left") {
  AutoOperator op(ShortTrack(), OperatorConfig{}, TreadDriveConfig{});
  const Vec2 p = ShortTrack().PointAt(0.1) + Vec2(0, -0.15);
  op.Observe(At(0.0, p, 0.0));
  CHECK(op.Decide(1.0).turn > 0.0);
}

TEST_CASE("facing backwards, the operator turns on the spot") {
  AutoOperator op(ShortTrack(), OperatorConfig{}, TreadDriveConfig{});
  op.Observe(At(0.0, ShortTrack().PointAt(0.1), std::numbers::pi));
  const auto intent = op.Decide(1.0);
  CHECK(intent.forward == 0.0);
  CHECK(std::abs(intent.turn) > 0.2);
}

TEST_CASE("after a bumper contact the operator backs off, turning away from the touched side") {
  OperatorConfig cfg;
  cfg.backoff_s = 0.8;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  Observation o = At(0.0, ShortTrack().PointAt(0.1), 0.0);
  o.bumper_left = true;
  op.Observe(o);
  const auto intent = op.Decide(0.5);
  CHECK(intent.forward < 0.0);
  CHECK(intent.turn < 0.0);  // reversing, rotating clockwise: away from the left contact
  CHECK(op.backing_off(1.0));
  op.Observe(At(1.0, ShortTrack().PointAt(0.1), 0.0));
  CHECK(op.Decide(1.5).forward > 0.0);  // contact gone, back to driving
}

TEST_CASE(
    "a contact that outlasts its back-off is not backed off again: the operator turns free and "
    "never backs away from the finish for good") {
  // Wedged a robot's length short of the finish line, facing it, its front
  // still touching after the back-off (blocked behind, where it has no
  // bumper): a minute of the same contact reverses it for one back-off only.
  OperatorConfig cfg;
  cfg.backoff_s = 0.8;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  const double length = ShortTrack().length();
  const Vec2 short_of_finish = ShortTrack().PointAt(length - 0.22);
  const double heading = std::atan2(ShortTrack().TangentAt(length - 0.22).y(),
                                    ShortTrack().TangentAt(length - 0.22).x());
  double reversing_s = 0.0;
  double last_turn = 0.0;
  constexpr double kStep = 0.01;
  for (double t = 0.0; t < 60.0; t += kStep) {
    Observation o = At(t, short_of_finish, heading);
    o.bumper_left = true;
    op.Observe(o);
    const auto intent = op.Decide(t);
    if (intent.forward < 0.0) reversing_s += kStep;
    last_turn = intent.turn;
    CHECK(intent.forward <= 0.0);  // never pushes on into what it touches
  }
  CHECK(reversing_s == Approx(cfg.backoff_s).margin(2 * kStep));
  CHECK(last_turn < 0.0);  // turning on the spot, away from the left contact
  // Once clear, it heads for the line.
  op.Observe(At(60.0, short_of_finish, heading));
  CHECK(op.Decide(60.0 + cfg.reaction_delay_s).forward > 0.0);
  // The bumpers let go and touch again: a new contact, backed off again.
  Observation again = At(60.5, short_of_finish, heading);
  again.bumper_right = true;
  op.Observe(again);
  CHECK(op.Decide(60.5 + cfg.reaction_delay_s).forward < 0.0);
}

TEST_CASE(
    "hitting again while aiming backs the operator off longer each time, and it looks closer "
    "ahead") {
  OperatorConfig cfg;
  cfg.reaction_delay_s = 0.0;
  cfg.backoff_s = 0.8;
  cfg.careful_s = 4.0;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  // Each contact comes after a clear state (the bumpers let go in between).
  const auto hit = [&op](double t) {
    op.Observe(At(t - 0.1, ShortTrack().PointAt(0.1), 0.0));
    Observation o = At(t, ShortTrack().PointAt(0.1), 0.0);
    o.bumper_right = true;
    op.Observe(o);
    op.Decide(t);
  };
  hit(0.0);
  CHECK(op.backing_off(0.79));
  CHECK_FALSE(op.backing_off(0.81));
  // A second contact at t = 2 (aiming until 4.8): twice as long.
  hit(2.0);
  CHECK(op.backing_off(3.59));
  CHECK_FALSE(op.backing_off(3.61));
  // A third: three times; the fourth and later stay at four.
  hit(4.0);
  CHECK(op.backing_off(6.39));
  CHECK_FALSE(op.backing_off(6.41));
  for (double t : {7.0, 11.0}) {
    hit(t);
    CHECK(op.backing_off(t + 3.19));
    CHECK_FALSE(op.backing_off(t + 3.21));
  }
  // Long after, a contact is a first one again.
  hit(40.0);
  CHECK_FALSE(op.backing_off(40.81));

  // Aiming, the operator steers harder onto the line from the same offset
  // (half the look-ahead: a sharper pursuit arc).
  const Vec2 beside = ShortTrack().PointAt(0.1) + Vec2(0.0, 0.06);
  AutoOperator relaxed(ShortTrack(), cfg, TreadDriveConfig{});
  relaxed.Observe(At(0.0, beside, 0.0));
  const double relaxed_turn = relaxed.Decide(0.0).turn;
  // op is aiming until 40.8 + 4 = 44.8.
  op.Observe(At(41.0, beside, 0.0));
  REQUIRE(op.careful(41.0));
  REQUIRE_FALSE(op.backing_off(41.0));
  const double aiming_turn = op.Decide(41.0).turn;
  CHECK(relaxed_turn < 0.0);  // left of the line: steer right
  CHECK(aiming_turn < relaxed_turn * 1.5);
}

TEST_CASE("the operator's arm lags its intent") {
  OperatorConfig cfg;
  cfg.arm_time_constant_s = 0.1;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  const interfaces::GestureInterface gesture{GestureConfig{}};
  op.Observe(At(0.0, ShortTrack().PointAt(0.1), 0.0));
  const auto first = op.Act(1.0, gesture);  // starts from neutral
  const auto after = op.Act(1.1, gesture);  // one time constant later
  const auto wanted = gesture.HandTargetsFor(op.Decide(1.1));
  const int right = haptics::Index(haptics::Side::kRight);
  REQUIRE(first[right]);
  REQUIRE(after[right]);
  const double goal = wanted[right]->position[0];
  CHECK(first[right]->position[0] == Approx(0.0));
  CHECK(after[right]->position[0] == Approx(goal * (1 - std::exp(-1.0))).epsilon(0.01));
  CHECK_FALSE(after[haptics::Index(haptics::Side::kLeft)]);
}

namespace {
/// An interface with one control to grasp: the left hand holds a grip at
/// x = 0.1 + 0.05·forward, approached from 4 cm above, closed to 1 rad.
struct GripInterface final : interfaces::MediatorInterface {
  std::string name() const override { return "grip"; }
  TreadCommand Update(double, const interfaces::VehicleFeedback&, haptics::Hal&) override {
    return {};
  }
  interfaces::HandTargets HandTargetsFor(const interfaces::MotionIntent& intent) const override {
    interfaces::HandGoal g;
    g.position = {0.1 + 0.05 * intent.forward, 0.0, 0.0};
    g.glove.fill(1.0);
    g.approach = {0.0, 0.0, 0.04};
    interfaces::HandTargets t;
    t[haptics::Index(haptics::Side::kLeft)] = g;
    return t;
  }
  bool NeedsPhysics() const override { return true; }
};
}  // namespace

TEST_CASE("with a control to grasp, the operator comes down open, closes, then drives") {
  OperatorConfig cfg;
  cfg.reaction_delay_s = 0.0;
  cfg.grasp_reach_s = 0.8;
  cfg.grasp_close_s = 0.6;
  AutoOperator op(ShortTrack(), cfg, TreadDriveConfig{});
  op.Observe(At(0.0, ShortTrack().PointAt(0.1), 0.0));  // on a straight: it wants to go forward
  const GripInterface grip;
  const int left = haptics::Index(haptics::Side::kLeft);

  auto at = [&](double t) { return *op.Act(t, grip)[left]; };
  const interfaces::HandGoal start = at(10.0);  // the first Act starts the grasp
  CHECK_FALSE(op.grasped(10.0));
  CHECK(start.position[2] == Approx(0.04));  // above the grip, open, at neutral
  CHECK(start.position[0] == Approx(0.1));
  CHECK(start.glove[5] == 0.0);
  const interfaces::HandGoal halfway = at(10.4);
  CHECK(halfway.position[2] > 0.0);
  CHECK(halfway.position[2] < 0.04);
  CHECK(halfway.glove[5] == 0.0);
  const interfaces::HandGoal down = at(10.8);  // on the grip, still open
  CHECK(down.position[2] == Approx(0.0).margin(1e-12));
  CHECK(down.glove[5] == Approx(0.0).margin(1e-12));
  CHECK(down.position[0] == Approx(0.1));  // not driving yet
  const interfaces::HandGoal closing = at(11.1);
  CHECK(closing.glove[5] > 0.1);
  CHECK(closing.glove[5] < 0.9);
  CHECK_FALSE(op.grasped(11.1));
  CHECK(op.grasped(11.4));
  const interfaces::HandGoal closed = at(11.4);
  CHECK(closed.glove[5] == Approx(1.0));
  // Driving: the grip moves forward with the intent, the fingers stay closed.
  const interfaces::HandGoal driving = at(12.4);
  CHECK(driving.position[0] > 0.1 + 0.05 * 0.5);
  CHECK(driving.glove[5] == 1.0);
}

TEST_CASE("with nothing to grasp the operator drives from its first act") {
  AutoOperator op(ShortTrack(), OperatorConfig{}, TreadDriveConfig{});
  const interfaces::GestureInterface gesture{GestureConfig{}};
  op.Act(5.0, gesture);
  CHECK(op.grasped(5.0));
}

TEST_CASE("a post in the band its body sweeps slows the operator down") {
  OperatorConfig cfg;
  cfg.reaction_delay_s = 0.0;
  // Beside the centre line, right of it, heading straight at gate 1's right post (0.2, -0.2).
  AutoOperator near(ShortTrack(), cfg, TreadDriveConfig{});
  near.Observe(At(0.0, Vec2(0.05, -0.2), 0.0));
  // The same pose with the gate far behind: nothing in the way.
  AutoOperator clear(ShortTrack(), cfg, TreadDriveConfig{});
  clear.Observe(At(0.0, Vec2(0.3, -0.2), 0.0));
  const double slowed = near.Decide(0.1).forward;
  CHECK(slowed > 0.0);
  CHECK(slowed < 0.5);
  CHECK(clear.Decide(0.1).forward > 0.6);
}

TEST_CASE(
    "a vehicle that turns less than asked is steered harder, one that turns as asked is not") {
  OperatorConfig cfg;
  cfg.reaction_delay_s = 0.0;
  const TreadDriveConfig drive;
  // Facing backwards, the operator turns on the spot; the vehicle answers
  // with `response` of the yaw rate the operator's model expects.
  const auto turn_after = [&](double response) {
    AutoOperator op(ShortTrack(), cfg, drive);
    const Vec2 p = ShortTrack().PointAt(0.1);
    double heading = std::numbers::pi;
    double turn = 0.0;
    for (double t = 0.0; t < 1.0; t += 0.02) {
      op.Observe(At(t, p, heading));
      turn = op.Decide(t).turn;
      heading += response * turn * 2.0 * drive.max_speed / drive.track_width * 0.02;
    }
    return std::abs(turn);
  };
  CHECK(turn_after(1.0) == Approx(0.4).margin(0.02));
  // A skidding tank turning as a 1.35x wider one: steered harder within a
  // second (towards 1.35x over its one-second memory), never past it.
  const double harder = turn_after(1.0 / 1.35);
  CHECK(harder > 0.4 * 1.12);
  CHECK(harder <= 0.4 * 1.35);
}
