// Stopping the physics world never waits for a step: its forces leave the HAL
// at once and its thread stops touching the HAL, while a step still runs; the
// scene builder stops adding bodies once told to. Behaviour only: every wait
// is a generous bound that ends the test on a fault, never a timing figure.
#include <atomic>
#include <catch2/catch.hpp>

#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/physics/scene_builder.hpp"
#include "haptel/physics/world.hpp"
#include "test_env.hpp"

namespace {

using haptel::PhysicsConfig;
using haptel::haptics::Side;
using haptel::physics::PhysicsWorld;

/// Holds the physics thread inside a step (BeforeStep) once `hold` is set,
/// until `release` (or a minute: a fault fails the test, never hangs it).
struct HoldingHook final : haptel::physics::StepHook {
  std::atomic<bool> hold{false};
  std::atomic<bool> held{false};
  std::atomic<bool> release{false};
  void BeforeStep() override {
    if (!hold.load()) return;
    held.store(true);
    haptel::test::WaitFor([&] { return release.load(); }, 60.0);
    held.store(false);
  }
};

}  // namespace

TEST_CASE("physics: RequestStop takes the hand's forces out of the HAL while a step still runs",
          "[physics][stop]") {
  haptel::haptics::Hal hal;
  haptel::haptics::WristRaw raw;
  raw.t_ns = haptel::MonotonicNs();
  raw.position = {10.0, 0.0, 5.0};
  hal.PublishWrist(Side::kRight, raw);

  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, -0.5);
  world.AddHand(Side::kRight);
  HoldingHook hook;
  world.AddStepHook(hook);
  world.Start(hal);
  REQUIRE(haptel::test::WaitFor([&] { return world.Counters().setpoints >= 20; }, 30.0));
  REQUIRE(hal.Setpoint(Side::kRight).coupling_enabled);

  hook.hold.store(true);
  REQUIRE(haptel::test::WaitFor([&] { return hook.held.load(); }, 30.0));
  world.RequestStop();  // returns while the step is held
  CHECK(hook.held.load());
  const auto stopped = hal.Setpoint(Side::kRight);
  CHECK_FALSE(stopped.coupling_enabled);
  CHECK_FALSE(world.Stop(0.05));  // the thread is still inside its step
  CHECK(world.running());

  hook.release.store(true);
  CHECK(world.Stop(60.0));
  CHECK_FALSE(world.running());
  // The step that ended after the stop wrote nothing to the HAL.
  const auto after = hal.Setpoint(Side::kRight);
  CHECK_FALSE(after.coupling_enabled);
  CHECK(after.stamp_ns == stopped.stamp_ns);
}

TEST_CASE("physics: the scene builder adds no body once cancelled", "[physics][stop]") {
  haptel::Scene scene;
  for (int i = 0; i < 3; ++i) {
    haptel::SceneObject ball;
    ball.name = "ball" + std::to_string(i);
    ball.dynamic = true;
    ball.mass = 0.1;
    ball.position = {0.0, 0.0, 0.5 + 0.01 * i};  // overlapping
    haptel::SceneShape sphere;
    sphere.kind = haptel::ShapeKind::kSphere;
    sphere.radius = 0.05;
    ball.shapes.push_back(sphere);
    scene.objects.push_back(ball);
  }
  std::atomic<bool> cancel{false};
  SECTION("not cancelled: every object") {
    PhysicsWorld world{PhysicsConfig{}};
    const auto built = haptel::physics::BuildScene(world, scene, &cancel);
    CHECK(built.nodes.size() == 3);
    CHECK(built.order.objects.size() == 3);
  }
  SECTION("cancelled: none, and the node order says so") {
    cancel.store(true);
    PhysicsWorld world{PhysicsConfig{}};
    const auto built = haptel::physics::BuildScene(world, scene, &cancel);
    CHECK(built.nodes.empty());
    CHECK(built.order.objects.empty());
    CHECK(built.order.dynamic_count == 0);
  }
}
