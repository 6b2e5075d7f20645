// The physics world and the proxy hands: following, contact, NaN recovery,
// unilateral finger forces, a two-hand grasp, the HAL hand-off, skipping.
#include <btBulletDynamicsCommon.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>

#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/physics/world.hpp"
#include "haptel/testing/box_grip.hpp"
#include "haptel/testing/vec_math.hpp"
#include "test_env.hpp"

namespace {

using haptel::PhysicsConfig;
using haptel::haptics::AxisAngle;
using haptel::haptics::Distance;
using haptel::haptics::HandSample;
using haptel::haptics::Side;
using haptel::haptics::TrackedHand;
using haptel::physics::PhysicsWorld;
using haptel::physics::Vec3d;
namespace ph = haptel::physics;

/// Angle (rad) between two unit quaternions.
double AngleBetween(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  const double dot = std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
  return 2.0 * std::acos(std::min(1.0, dot));
}

/// Runs `steps` fixed steps with the hand of `side` tracking `sample`.
void Run(PhysicsWorld& world, Side side, const HandSample& sample, int steps) {
  for (int i = 0; i < steps; ++i) {
    world.hand(side)->SetTracked(sample);
    world.Step();
  }
}

}  // namespace

TEST_CASE("physics: the shipped file loads, strictly", "[physics]") {
  const PhysicsConfig c = haptel::LoadPhysics(haptel::ShippedFile("config/physics.yaml"));
  const PhysicsConfig d;
  CHECK(c.step_s == d.step_s);
  CHECK(c.solver_iterations == d.solver_iterations);
  CHECK(c.hand.palm_mass == d.hand.palm_mass);
  CHECK(c.hand.phalanx_mass == d.hand.phalanx_mass);
  CHECK(c.hand.coupling_linear_stiffness == d.hand.coupling_linear_stiffness);
  CHECK(c.hand.feedback_stiffness == d.hand.feedback_stiffness);
  CHECK(c.hand.material.friction == d.hand.material.friction);
  CHECK(c.hand.material.rolling_friction == d.hand.material.rolling_friction);
  CHECK(c.hand.material.spinning_friction == d.hand.material.spinning_friction);
  CHECK(c.hand.material.rolling_friction > 0.0);

  const auto dir = haptel::test::ScratchDir("physics-config");
  const auto file = dir / "bad.yaml";
  {
    std::ofstream out(file);
    out << "step_s: 0.001\nhand:\n  palm_mass: 0.35\n  palm_masss: 0.2\n";
  }
  REQUIRE_THROWS_AS(haptel::LoadPhysics(file), haptel::ConfigError);
  REQUIRE_THROWS_WITH(haptel::LoadPhysics(file), Catch::Contains("hand.palm_masss"));
  {
    std::ofstream out(file);
    out << "step_s: 0.5\n";
  }
  REQUIRE_THROWS_WITH(haptel::LoadPhysics(file), Catch::Contains("step_s"));
  {
    std::ofstream out(file);
    out << "hand:\n  material:\n    rolling_friction: 0.2\n";
  }
  REQUIRE_THROWS_WITH(haptel::LoadPhysics(file), Catch::Contains("hand.material.rolling_friction"));
  {  // Bullet would silently ignore spinning friction without rolling friction.
    std::ofstream out(file);
    out << "hand:\n  material:\n    rolling_friction: 0\n    spinning_friction: 0.002\n";
  }
  REQUIRE_THROWS_WITH(haptel::LoadPhysics(file),
                      Catch::Contains("hand.material.spinning_friction"));
  {
    std::ofstream out(file);
    out << "hand:\n  material:\n    rolling_friction: 0\n";
  }
  REQUIRE_THROWS_WITH(haptel::LoadPhysics(file), Catch::Contains("hand.material.rolling_friction"));
}

TEST_CASE("physics: no world is created when nothing needs one", "[physics]") {
  const uint64_t before = PhysicsWorld::worlds_created();
  // The gesture interface: no physical controls, a scene without bodies.
  const ph::PhysicsNeeds gesture{};
  CHECK_FALSE(ph::NeedsWorld(gesture));
  CHECK(PhysicsWorld::CreateIfNeeded(PhysicsConfig{}, gesture) == nullptr);
  CHECK(PhysicsWorld::worlds_created() == before);

  CHECK(ph::NeedsWorld({true, 0}));
  CHECK(ph::NeedsWorld({false, 2}));
  auto world = PhysicsWorld::CreateIfNeeded(PhysicsConfig{}, {true, 0});
  CHECK(world != nullptr);
  CHECK(PhysicsWorld::worlds_created() == before + 1);
}

TEST_CASE("physics: the proxy palm follows a moving tracked wrist", "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddHand(Side::kRight);
  ph::ProxyHand& hand = *world.hand(Side::kRight);
  CHECK(hand.clamped_axes() == 0);  // the defaults are as stiff as configured
  const double h = world.config().step_s;

  // 0.2 m/s along a diagonal for 0.5 s, while turning 0.6 rad about z.
  double worst_moving = 0.0;
  Vec3d p{0.0, 0.0, 0.1};
  const int moving = 500;
  for (int i = 0; i < moving; ++i) {
    const double t = i * h;
    p = {0.2 * t * 0.8, 0.2 * t * 0.6, 0.1};
    Run(world, Side::kRight, TrackedHand(p, AxisAngle({0, 0, 1}, 1.2 * t)), 1);
    if (i > 100) worst_moving = std::max(worst_moving, Distance(hand.ProxyWrist().position, p));
  }
  const HandSample hold = TrackedHand(p, AxisAngle({0, 0, 1}, 1.2 * moving * h));
  Run(world, Side::kRight, hold, 500);
  const double steady = Distance(hand.ProxyWrist().position, hold.position);
  INFO("error while moving at 0.2 m/s: " << worst_moving * 1e3 << " mm; at rest: " << steady * 1e3
                                         << " mm");
  CHECK(worst_moving < 0.005);
  CHECK(steady < 1e-4);
  CHECK(AngleBetween(hand.ProxyWrist().orientation, hold.orientation) < 1e-3);
  // With nothing in the way the fingers sit on the tracked ones: no finger force.
  for (double f : hand.FingerForces()) CHECK(f < 0.01);
}

TEST_CASE("physics: finger joints follow the glove angles", "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddHand(Side::kLeft);
  ph::ProxyHand& hand = *world.hand(Side::kLeft);
  HandSample s = TrackedHand({0.0, 0.0, 0.2});
  s.finger_angles[4] = 0.6;   // index MCP
  s.finger_angles[5] = 0.8;   // index PIP
  s.finger_angles[6] = 0.4;   // index DIP
  s.finger_angles[16] = 0.2;  // index-middle abduction
  s.finger_angles[1] = 0.5;   // thumb MCP
  Run(world, Side::kLeft, TrackedHand({0.0, 0.0, 0.2}), 10);
  Run(world, Side::kLeft, s, 1500);
  CHECK(hand.FlexionAngle(ph::kIndex, 0) == Approx(0.6).margin(0.01));
  CHECK(hand.FlexionAngle(ph::kIndex, 1) == Approx(0.8).margin(0.01));
  CHECK(hand.FlexionAngle(ph::kIndex, 2) == Approx(0.4).margin(0.01));
  for (int f = 0; f < ph::kFingers; ++f) {
    INFO("finger " << f);
    CHECK(Distance(hand.ProxyTip(f), hand.TrackedTip(f)) < 1e-3);
  }
  // Flexion curls towards the palm (−z for a palm-down hand).
  CHECK(hand.ProxyTip(ph::kIndex)[2] < 0.2 - 0.03);
  CHECK(hand.ProxyTip(ph::kMiddle)[2] == Approx(0.2).margin(1e-3));
}

TEST_CASE("physics: a 10 N push into a table penetrates a few millimetres at most", "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticBox({0.0, 0.0, -0.05}, {0.5, 0.5, 0.05});  // table top at z = 0
  world.AddHand(Side::kRight);
  ph::ProxyHand& hand = *world.hand(Side::kRight);
  const auto& hc = world.config().hand;
  const double half_thickness = hc.palm_half_extents[2];
  const double push = 10.0 / hc.coupling_linear_stiffness;  // tracked below the surface by F/k

  // Come down from 3 cm above at 0.1 m/s, then hold the tracked wrist below the surface.
  const double target_z = half_thickness - push;
  double z = half_thickness + 0.03;
  double worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    z = std::max(target_z, z - 0.1 * world.config().step_s);
    Run(world, Side::kRight, TrackedHand({0.0, 0.0, z}), 1);
    worst = std::max(worst, half_thickness - hand.ProxyWrist().position[2]);
  }
  const double palm_z = hand.ProxyWrist().position[2];
  const double penetration = half_thickness - palm_z;
  const double coupling_force = hc.coupling_linear_stiffness * (palm_z - target_z);
  WARN("penetration under a " << coupling_force << " N push: " << penetration * 1e3
                              << " mm at rest, " << worst * 1e3 << " mm worst");
  CHECK(coupling_force == Approx(10.0).margin(1.0));
  CHECK(penetration < 0.002);
  CHECK(worst < 0.003);

  // The set-point asks the servo loop to push the operator's hand back up.
  haptel::haptics::ForceSetpoint sp;
  sp.field.enabled = true;
  sp.field.stiffness = 42.0;
  hand.FillSetpoint(sp);
  CHECK(sp.coupling_enabled);
  CHECK(sp.field.stiffness == 42.0);  // other fields kept
  const double servo_force = sp.coupling_stiffness * (sp.coupling_target[2] - target_z);
  CHECK(servo_force > 0.0);
}

TEST_CASE("physics: a NaN body resets its hand to the tracked pose and the world goes on",
          "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  const ph::BodyId ball = world.AddDynamicSphere({0.5, 0.0, 1.0}, 0.02, 0.1);
  world.AddHand(Side::kRight);
  ph::ProxyHand& hand = *world.hand(Side::kRight);
  const HandSample s = TrackedHand({0.0, 0.1, 0.2}, AxisAngle({1, 0, 0}, 0.3));
  Run(world, Side::kRight, s, 50);
  REQUIRE(world.Counters().hand_resets == 0);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  hand.palm_body().setLinearVelocity(btVector3(nan, 0, 0));
  const double ball_z = world.BodyPose(ball).position[2];
  world.Step();
  CHECK(world.Counters().hand_resets == 1);
  CHECK(hand.Finite());
  CHECK(Distance(hand.ProxyWrist().position, s.position) < 1e-9);
  CHECK(Distance(hand.ProxyTip(ph::kIndex), hand.TrackedTip(ph::kIndex)) < 1e-9);

  Run(world, Side::kRight, s, 200);
  CHECK(world.Counters().hand_resets == 1);
  CHECK(world.Counters().steps == 251);
  CHECK(hand.Finite());
  CHECK(Distance(hand.ProxyWrist().position, s.position) < 1e-4);
  CHECK(world.BodyPose(ball).position[2] < ball_z - 0.1);  // the ball kept falling

  // A scene body goes back where it was made.
  world.body(ball).setAngularVelocity(btVector3(0, std::numeric_limits<double>::infinity(), 0));
  world.Step();
  CHECK(world.Counters().body_resets == 1);
  CHECK(world.BodyPose(ball).position[2] == Approx(1.0));
}

TEST_CASE("physics: finger forces are unilateral along the nail normal", "[physics]") {
  const auto& hc = PhysicsConfig{}.hand;
  // Right hand, palm down at z = 0.1: the index lies along x at y ≈ 0.027.
  const double z = 0.1;
  const double finger_bottom = z - hc.phalanx_radius;
  const double finger_top = z + hc.phalanx_radius;
  const double x0 = 2.0 * hc.palm_half_extents[0] + hc.phalanx_length[0];  // index PIP
  const double y = 0.675 * hc.palm_half_extents[1];

  SECTION("the tracked finger bends into an object: force") {
    PhysicsWorld world{PhysicsConfig{}};
    world.AddStaticBox({x0 + 0.025, y, finger_bottom - 0.0005 - 0.01}, {0.025, 0.006, 0.01});
    world.AddHand(Side::kRight);
    ph::ProxyHand& hand = *world.hand(Side::kRight);
    Run(world, Side::kRight, TrackedHand({0, 0, z}), 100);
    CHECK(hand.FingerForces()[ph::kIndex] < 0.01);
    HandSample s = TrackedHand({0, 0, z});
    s.finger_angles[5] = 0.9;  // index PIP
    s.finger_angles[6] = 0.6;  // index DIP
    Run(world, Side::kRight, s, 1000);
    const auto forces = hand.FingerForces();
    INFO("index force " << forces[ph::kIndex] << " N");
    CHECK(hand.ProxyTip(ph::kIndex)[2] > hand.TrackedTip(ph::kIndex)[2] + 0.01);  // held back
    CHECK(forces[ph::kIndex] > 2.0);
    for (int f : {ph::kThumb, ph::kMiddle, ph::kRing, ph::kPinky}) CHECK(forces[f] < 0.05);
  }
  SECTION("the tracked finger pulls away from an object pressing its back: no force") {
    PhysicsWorld world{PhysicsConfig{}};
    world.AddStaticBox({x0 + 0.025, y, finger_top + 0.0005 + 0.01}, {0.025, 0.006, 0.01});
    world.AddHand(Side::kRight);
    ph::ProxyHand& hand = *world.hand(Side::kRight);
    Run(world, Side::kRight, TrackedHand({0, 0, z}), 100);
    HandSample s = TrackedHand({0, 0, z});
    s.finger_angles[5] = -0.9;  // index PIP bent backwards, into the object above it
    s.finger_angles[6] = -0.6;
    Run(world, Side::kRight, s, 1000);
    CHECK(hand.ProxyTip(ph::kIndex)[2] < hand.TrackedTip(ph::kIndex)[2] - 0.01);  // held back
    CHECK(hand.FingerForces()[ph::kIndex] == 0.0);
  }
}

TEST_CASE("physics: two palms squeeze a 0.5 kg box and lift it", "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  const ph::BoxGrip grip(world);
  const double half = ph::BoxGrip::kHalf;
  const ph::BodyId box = grip.box;
  const double squeeze = 0.01;  // tracked palms 1 cm inside the box: ≈30 N each
  const double z0 = 0.09;
  auto step = [&](double z) {
    grip.Track(squeeze, z);
    world.Step();
  };
  for (int i = 0; i < 300; ++i) step(z0);  // close the grip
  CHECK(world.BodyPose(box).position[2] == Approx(half).margin(0.002));
  for (int i = 0; i < 1000; ++i) step(z0 + 0.1 * i * 1e-3);  // lift 10 cm in 1 s
  for (int i = 0; i < 500; ++i) step(z0 + 0.1);
  const Vec3d p = world.BodyPose(box).position;
  INFO("box at " << p[0] << ", " << p[1] << ", " << p[2]);
  CHECK(p[2] > half + 0.09);
  CHECK(std::abs(p[1]) < 0.005);
  CHECK(world.Counters().hand_resets == 0);
}

TEST_CASE("physics: a phalanx capsule resting or pressed on a box does not roll", "[physics]") {
  // A distal phalanx alone (the hand's material) lying on a heavy box: no
  // torque acts about its axis, so it must not roll. Without rolling friction
  // Bullet's cached contact points trail the axis as it turns and the normal
  // force on them spins it up until it rolls off (stability bench, mass_ratio).
  const PhysicsConfig config;
  PhysicsWorld world{config};
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const double half = 0.1;
  const ph::BodyId box = world.AddDynamicBox({0, 0, half}, {half, half, half}, 9.0);
  const double r = config.hand.phalanx_radius, mass = config.hand.phalanx_mass[2];
  auto shape = std::make_unique<btCapsuleShapeX>(r, config.hand.phalanx_length[2] - 2.0 * r);
  btVector3 inertia;
  shape->calculateLocalInertia(mass, inertia);
  ph::Pose pose;
  pose.position = {0.0, 0.0, 2.0 * half + r};
  const ph::BodyId id =
      world.AddRigidBody(std::move(shape), {}, mass, {inertia.x(), inertia.y(), inertia.z()}, pose,
                         config.hand.material);
  btRigidBody& capsule = world.body(id);
  capsule.setActivationState(DISABLE_DEACTIVATION);
  world.body(box).setActivationState(DISABLE_DEACTIVATION);
  double spin = 0.0;  // max |ω| about the capsule's axis after the first contact settled
  for (int i = 0; i < 4000; ++i) {
    if (i >= 2500) capsule.applyCentralForce(btVector3(0, 0, -5.0));  // a 5 N press
    world.Step();
    const btVector3 axis = capsule.getWorldTransform().getBasis().getColumn(0);
    if (i >= 500) spin = std::max(spin, std::abs(capsule.getAngularVelocity().dot(axis)));
  }
  const Vec3d p = world.BodyPose(id).position;
  INFO("spin " << spin << " rad/s, capsule at " << p[0] << ", " << p[1] << ", " << p[2]);
  CHECK(spin < 0.1);  // the unfixed contact reached 0.6 rad/s at rest, tens of rad/s pressed
  CHECK(std::hypot(p[0], p[1]) < 0.002);
  CHECK(p[2] == Approx(2.0 * half + r).margin(0.001));
}

TEST_CASE(
    "physics: a sleeping box stays put; a palm pushing it wakes it and slides it on the floor",
    "[physics]") {
  // The world skips sleeping bodies (no bounding-box refresh, no integration):
  // a sleeping body must not move at all, and once woken it must collide
  // where it went.
  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const double half = 0.05;
  const ph::BodyId box = world.AddDynamicBox({0, 0, half}, {half, half, half}, 0.5);
  world.AddHand(Side::kRight);
  // Fingers up, the palm facing +x (turned −90° about y), level with the box.
  const auto q = AxisAngle({0, 1, 0}, -M_PI / 2);
  const double wrist_z = half + 0.005 - world.config().hand.palm_half_extents[0];
  auto step_at = [&](double x) {
    world.hand(Side::kRight)->SetTracked(TrackedHand({x, 0.0, wrist_z}, q));
    world.Step();
  };
  for (int i = 0; i < 3000; ++i) step_at(-0.3);
  REQUIRE(world.BodySleeping(box));
  const ph::Pose asleep = world.BodyPose(box);
  for (int i = 0; i < 500; ++i) step_at(-0.3);
  CHECK(world.BodySleeping(box));
  CHECK(world.BodyPose(box).position == asleep.position);
  CHECK(world.BodyPose(box).orientation == asleep.orientation);

  for (int i = 0; i < 1500; ++i) step_at(-0.3 + 0.4 * i / 1500.0);  // to x = 0.1 in 1.5 s
  for (int i = 0; i < 500; ++i) step_at(0.1);
  const Vec3d p = world.BodyPose(box).position;
  INFO("box at " << p[0] << ", " << p[1] << ", " << p[2]);
  CHECK(p[0] > 0.1);                          // pushed: its back face is at the palm
  CHECK(p[2] == Approx(half).margin(0.002));  // still on the floor where it went
  CHECK(std::abs(p[1]) < 0.02);
  CHECK(world.Counters().body_resets == 0);
}

TEST_CASE("physics: a box at rest on a table falls asleep", "[physics]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const ph::BodyId box = world.AddDynamicBox({0, 0, 0.051}, {0.05, 0.05, 0.05}, 0.5);
  for (int i = 0; i < 4000; ++i) world.Step();
  CHECK(world.BodySleeping(box));
  CHECK(world.BodyPose(box).position[2] == Approx(0.05).margin(0.002));
}

TEST_CASE("physics: the thread reads hands from the HAL and writes set-points", "[physics]") {
  haptel::haptics::Hal hal;  // default calibration: tracker 0.01 m per unit, glove 1 rad per unit
  haptel::haptics::WristRaw raw;
  raw.t_ns = haptel::MonotonicNs();
  raw.position = {10.0, 0.0, 5.0};  // (0.10, 0, 0.05) m
  hal.PublishWrist(Side::kRight, raw);
  haptel::haptics::GloveRaw glove;
  glove.t_ns = raw.t_ns;
  glove.sensors[4] = 0.3;
  hal.PublishGlove(Side::kRight, glove);
  haptel::haptics::ForceField field;
  field.enabled = true;
  field.stiffness = 42.0;
  hal.SetField(Side::kRight, field);

  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, -0.5);
  world.AddHand(Side::kRight);
  world.Start(hal);
  REQUIRE(haptel::test::WaitFor([&] { return world.Counters().setpoints >= 50; }, 10.0));
  const auto sp = hal.Setpoint(Side::kRight);
  world.Stop();

  CHECK(sp.coupling_enabled);
  CHECK(sp.stamp_ns > 0);
  CHECK(sp.coupling_stiffness == world.config().hand.feedback_stiffness);
  CHECK(sp.coupling_damping == world.config().hand.feedback_damping);
  CHECK(Distance(sp.coupling_target, {0.10, 0.0, 0.05}) < 0.002);
  CHECK(sp.field.enabled);
  CHECK(sp.field.stiffness == 42.0);
  CHECK(world.Poses(Side::kRight).valid);
  CHECK_FALSE(world.Poses(Side::kLeft).valid);
  CHECK(world.Stats().ticks > 0);
  CHECK(world.Counters().invalid_samples == 0);
  CHECK_FALSE(hal.Setpoint(Side::kLeft).coupling_enabled);  // no left hand: untouched

  // Stopped: no coupling to a proxy that no longer moves; the field stays.
  const auto after = hal.Setpoint(Side::kRight);
  CHECK_FALSE(after.coupling_enabled);
  CHECK(after.field.stiffness == 42.0);
}

TEST_CASE("physics: a world refuses a config ValidateOrThrow refuses, before building anything",
          "[physics]") {
  PhysicsConfig c;
  c.hand.phalanx_radius = 0.2;
  const std::string what =
      haptel::test::WhatOf<haptel::ConfigFieldError>([&] { PhysicsWorld world(c); });
  CHECK_THAT(what, Catch::Contains("hand.phalanx_radius: expected a number in [0.001, 0.05]"));
  c = PhysicsConfig{};
  c.step_s = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_AS(PhysicsWorld(c), std::invalid_argument);  // the type derives from it
}
