// Parking: sleeping scene bodies leave the Bullet world and come back, awake,
// before anything can touch them — a palm, a rolling ball, a stack woken
// together — and then move as they would have without parking. A parked body
// keeps its pose, its scene node's pose and everything Bullet would have kept;
// stepping a world with parked bodies allocates nothing.
#include <btBulletDynamicsCommon.h>

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <span>
#include <utility>
#include <vector>

#include "alloc_counter.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/physics/scene_builder.hpp"
#include "haptel/physics/world.hpp"
#include "haptel/testing/vec_math.hpp"

namespace {

using haptel::PhysicsConfig;
using haptel::haptics::AxisAngle;
using haptel::haptics::Side;
using haptel::haptics::TrackedHand;
using haptel::physics::PhysicsWorld;
using haptel::physics::Vec3d;
namespace ph = haptel::physics;

constexpr double kHalf = 0.05;  ///< m, the boxes' half size

bool InBulletWorld(PhysicsWorld& world, ph::BodyId id) {
  const btCollisionObjectArray& objects = world.bullet().getCollisionObjectArray();
  const btCollisionObject* body = &std::as_const(world).body(id);
  return objects.findLinearSearch(const_cast<btCollisionObject*>(body)) < objects.size();
}

double Distance(const Vec3d& a, const Vec3d& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}
/// Angle (rad) between two unit quaternions.
double AngleBetween(const std::array<double, 4>& a, const std::array<double, 4>& b) {
  const double dot = std::abs(a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]);
  return 2.0 * std::acos(std::min(1.0, dot));
}

/// The right palm facing +x (fingers up), level with a box on the floor,
/// swept along x: from `x0` it waits 3 s (the boxes fall asleep), moves to
/// `x1` in 1.5 s and stays 0.5 s. Calls `each(step)` after every step.
template <typename Each>
void SweepPalm(PhysicsWorld& world, double x0, double x1, Each&& each) {
  const auto q = AxisAngle({0, 1, 0}, -M_PI / 2);
  const double wrist_z = kHalf + 0.005 - world.config().hand.palm_half_extents[0];
  int step = 0;
  auto step_at = [&](double x) {
    world.hand(Side::kRight)->SetTracked(TrackedHand({x, 0.0, wrist_z}, q));
    world.Step();
    each(step++);
  };
  for (int i = 0; i < 3000; ++i) step_at(x0);
  for (int i = 0; i < 1500; ++i) step_at(x0 + (x1 - x0) * i / 1500.0);
  for (int i = 0; i < 500; ++i) step_at(x1);
}

}  // namespace

TEST_CASE("parking: a body that falls asleep leaves the Bullet world; the world counts it",
          "[physics][parking]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const ph::BodyId box = world.AddDynamicBox({0, 0, kHalf + 0.001}, {kHalf, kHalf, kHalf}, 0.5);
  world.Step();
  CHECK(world.Counters().awake_bodies == 1);
  CHECK(world.Counters().parked_bodies == 0);
  int steps = 1;
  while (!world.BodySleeping(box) && steps < 4000) {
    world.Step();
    ++steps;
  }
  REQUIRE(world.BodySleeping(box));
  // Parked by the step that put it to sleep.
  CHECK(world.BodyParked(box));
  CHECK_FALSE(InBulletWorld(world, box));
  const ph::PhysicsCounters c = world.Counters();
  CHECK(c.parked_bodies == 1);
  CHECK(c.awake_bodies == 0);
  CHECK(c.parkings == 1);
  CHECK(c.wakings == 0);
  CHECK(world.BodyPose(box).position[2] == Approx(kHalf).margin(0.002));
  CHECK(world.BodyVelocity(box) == Vec3d{0, 0, 0});
  // Nothing comes near: it stays parked, where it was.
  const ph::Pose parked = world.BodyPose(box);
  for (int i = 0; i < 1000; ++i) world.Step();
  CHECK(world.BodyParked(box));
  CHECK(world.BodyPose(box).position == parked.position);
  CHECK(world.BodyPose(box).orientation == parked.orientation);
  CHECK(world.Counters().parkings == 1);
}

TEST_CASE("parking: a palm moving into a parked box wakes it and pushes it as without parking",
          "[physics][parking]") {
  struct Run {
    ph::Pose end;
    ph::Pose asleep;
    int woken_at = -1;  ///< the step after which the box was first awake again
    bool parked_before = false;
    ph::PhysicsCounters counters;
  };
  auto run = [](bool parking) {
    PhysicsWorld world{PhysicsConfig{}};
    world.SetParking(parking);
    world.AddStaticPlane({0, 0, 1}, 0.0);
    haptel::PhysicsMaterial material;
    material.friction = 0.7;
    material.restitution = 0.1;
    const ph::BodyId box = world.AddDynamicBox({0, 0, kHalf}, {kHalf, kHalf, kHalf}, 0.5, material);
    // A filter and a gravity of its own, which waking must keep.
    btRigidBody& b = world.body(box);
    world.bullet().removeRigidBody(&b);
    const int group = btBroadphaseProxy::DefaultFilter | 512;
    const int mask = btBroadphaseProxy::AllFilter & ~1024;
    world.bullet().addRigidBody(&b, group, mask);
    b.setGravity(btVector3(0.2, 0, -9.0));
    world.AddHand(Side::kRight);
    Run r;
    SweepPalm(world, -0.3, 0.1, [&](int step) {
      if (step == 2999) {
        r.parked_before = world.BodyParked(box);
        r.asleep = world.BodyPose(box);
      }
      if (step >= 3000 && r.woken_at < 0 && !world.BodySleeping(box)) {
        r.woken_at = step;
        // Woken as it was: its filter, gravity and material.
        const btRigidBody& body = std::as_const(world).body(box);
        REQUIRE(body.getBroadphaseHandle() != nullptr);
        CHECK(body.getBroadphaseHandle()->m_collisionFilterGroup == group);
        CHECK(body.getBroadphaseHandle()->m_collisionFilterMask == mask);
        CHECK(body.getGravity() == btVector3(0.2, 0, -9.0));
        CHECK(body.getFriction() == 0.7);
        CHECK(body.getRestitution() == 0.1);
      }
    });
    r.end = world.BodyPose(box);
    r.counters = world.Counters();
    return r;
  };
  const Run with = run(true);
  const Run without = run(false);
  CHECK(with.parked_before);
  CHECK_FALSE(without.parked_before);
  CHECK(with.counters.parkings >= 1);
  CHECK(with.counters.wakings >= 1);
  CHECK(without.counters.parkings == 0);
  // Asleep at the same pose, woken before the palm reached it, and pushed.
  CHECK(with.asleep.position == without.asleep.position);
  REQUIRE(with.woken_at >= 0);
  INFO("woken after step " << with.woken_at << " (without parking " << without.woken_at << ")");
  INFO("box at " << with.end.position[0] << ", " << with.end.position[1] << ", "
                 << with.end.position[2] << " (without parking " << without.end.position[0] << ", "
                 << without.end.position[1] << ", " << without.end.position[2] << ")");
  INFO("turned " << AngleBetween(with.end.orientation, without.end.orientation) << " rad apart");
  CHECK(with.end.position[0] > 0.1);
  CHECK(with.end.position[2] == Approx(kHalf).margin(0.002));
  CHECK(Distance(with.end.position, without.end.position) < 0.002);
  CHECK(AngleBetween(with.end.orientation, without.end.orientation) < 0.02);
}

TEST_CASE(
    "parking: a body pushed into a parked stack wakes both boxes at once; they move as without "
    "parking",
    "[physics][parking]") {
  // A 5 kg box that never sleeps (as a hand), driven along x at 0.2 m/s
  // (its velocity set before each step) into a stack of two boxes 3 cm off
  // its centre line, pushing and turning it. A slow push: an impact (a ball
  // rolling into the stack) comes out differently in Bullet for a start
  // speed 0.01 % off, parking or not.
  struct Run {
    std::array<ph::Pose, 2> end;
    std::array<int, 2> woken_at{-1, -1};
    double gap_at_wake = 0.0;  ///< m, between the pusher's front and the stack
    bool parked_before = false;
    ph::PhysicsCounters counters;
  };
  auto run = [](bool parking) {
    PhysicsWorld world{PhysicsConfig{}};
    world.SetParking(parking);
    world.AddStaticPlane({0, 0, 1}, 0.0);
    const std::array<ph::BodyId, 2> stack{
        world.AddDynamicBox({0, 0.03, kHalf}, {kHalf, kHalf, kHalf}, 0.5),
        world.AddDynamicBox({0, 0.03, 3 * kHalf + 0.001}, {kHalf, kHalf, kHalf}, 0.5)};
    const double pusher_half_x = 0.05;
    const ph::BodyId pusher = world.AddDynamicBox({-0.4, 0, 0.04}, {pusher_half_x, 0.1, 0.04}, 5.0);
    world.body(pusher).setActivationState(DISABLE_DEACTIVATION);
    Run r;
    for (int i = 0; i < 3000; ++i) world.Step();
    r.parked_before = world.BodyParked(stack[0]) && world.BodyParked(stack[1]);
    for (int i = 0; i < 3500; ++i) {
      if (i < 2500) world.body(pusher).setLinearVelocity(btVector3(0.2, 0, 0));
      world.Step();
      for (int k = 0; k < 2; ++k) {
        if (r.woken_at[k] >= 0 || world.BodySleeping(stack[k])) continue;
        r.woken_at[k] = i;
        if (k == 0) {
          r.gap_at_wake = (world.BodyPose(stack[0]).position[0] - kHalf) -
                          (world.BodyPose(pusher).position[0] + pusher_half_x);
        }
      }
    }
    for (int k = 0; k < 2; ++k) r.end[k] = world.BodyPose(stack[k]);
    r.counters = world.Counters();
    return r;
  };
  const Run with = run(true);
  const Run without = run(false);
  CHECK(with.parked_before);
  CHECK_FALSE(without.parked_before);
  REQUIRE(with.woken_at[0] >= 0);
  INFO("woken after step " << with.woken_at[0] << " " << with.gap_at_wake
                           << " m away (without parking " << without.woken_at[0] << ", "
                           << without.gap_at_wake << " m)");
  // Woken before the pusher touched it, the box on top in the same step (in
  // contact: one island).
  CHECK(with.gap_at_wake > 0.01);
  CHECK(with.woken_at[1] == with.woken_at[0]);
  CHECK(with.counters.wakings >= 2);
  CHECK(without.counters.wakings == 0);
  for (int k = 0; k < 2; ++k) {
    INFO("box " << k << " at " << with.end[k].position[0] << ", " << with.end[k].position[1] << ", "
                << with.end[k].position[2] << " (without parking " << without.end[k].position[0]
                << ", " << without.end[k].position[1] << ", " << without.end[k].position[2] << ")");
    CHECK(with.end[k].position[0] > 0.15);  // pushed, the top box riding on the bottom one
    CHECK(with.end[k].position[2] == Approx(without.end[k].position[2]).margin(0.002));
    // Where it ends varies in Bullet itself, parking or not: for push speeds
    // 0.05 % apart, by 6 mm along x and y and 0.07 rad of its 0.45 rad turn.
    CHECK(std::abs(with.end[k].position[0] - without.end[k].position[0]) < 0.008);
    CHECK(std::abs(with.end[k].position[1] - without.end[k].position[1]) < 0.012);
    CHECK(AngleBetween(with.end[k].orientation, without.end[k].orientation) < 0.1);
  }
}

TEST_CASE("parking: a parked body keeps its pose, and its scene node the object's pose",
          "[physics][parking][scene]") {
  const haptel::Scene scene = haptel::LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  PhysicsWorld world{PhysicsConfig{}};
  const ph::BuiltScene built = ph::BuildScene(world, scene);
  REQUIRE(built.order.dynamic_count == 1);
  const ph::SceneBody& node = built.nodes[0];
  REQUIRE(node.dynamic);
  int steps = 0;
  while (!world.BodyParked(node.body) && steps < 5000) {
    world.Step();
    ++steps;
  }
  REQUIRE(world.BodyParked(node.body));
  const ph::Pose body = world.BodyPose(node.body);
  const ph::Pose object = ph::ObjectPose(world, node);
  // On the table where the file puts it (settled by a fraction of a millimetre).
  const haptel::SceneObject& o = scene.objects[node.object];
  CHECK(Distance(object.position, {o.position.x(), o.position.y(), o.position.z()}) < 0.002);
  for (int i = 0; i < 500; ++i) world.Step();
  CHECK(world.BodyParked(node.body));
  CHECK(world.BodyPose(node.body).position == body.position);
  CHECK(world.BodyPose(node.body).orientation == body.orientation);
  // Synchronising the view's nodes reads the parked body's pose as it is.
  std::vector<ph::SceneBody> nodes = built.nodes;
  std::vector<ph::Pose> synced;
  const std::size_t n = haptel::SyncPoses(
      std::span<ph::SceneBody>(nodes), [](const ph::SceneBody& s) { return s.dynamic; },
      [&](const ph::SceneBody& s) { synced.push_back(ph::ObjectPose(world, s)); });
  REQUIRE(n == 1);
  CHECK(synced[0].position == object.position);
  CHECK(synced[0].orientation == object.orientation);
}

TEST_CASE(
    "parking: body() brings a parked body back asleep; parking off keeps sleeping bodies in the "
    "world",
    "[physics][parking]") {
  PhysicsWorld world{PhysicsConfig{}};
  world.AddStaticPlane({0, 0, 1}, 0.0);
  const ph::BodyId a = world.AddDynamicBox({0, 0, kHalf}, {kHalf, kHalf, kHalf}, 0.5);
  const ph::BodyId b = world.AddDynamicBox({1, 0, kHalf}, {kHalf, kHalf, kHalf}, 0.5);
  for (int i = 0; i < 3000; ++i) world.Step();
  REQUIRE(world.BodyParked(a));
  REQUIRE(world.BodyParked(b));
  // Reading through the const world leaves it parked; body() for changes brings it back.
  CHECK(std::as_const(world).body(a).getActivationState() == ISLAND_SLEEPING);
  CHECK(world.BodyParked(a));
  world.body(a);
  CHECK_FALSE(world.BodyParked(a));
  CHECK(InBulletWorld(world, a));
  CHECK(world.BodySleeping(a));
  world.Step();  // still asleep, nothing near: parked again
  CHECK(world.BodyParked(a));

  world.SetParking(false);
  CHECK_FALSE(world.BodyParked(a));
  CHECK_FALSE(world.BodyParked(b));
  CHECK(world.Counters().parked_bodies == 0);
  for (int i = 0; i < 100; ++i) world.Step();
  CHECK(InBulletWorld(world, a));
  CHECK(InBulletWorld(world, b));
  CHECK(world.BodySleeping(a));
  CHECK(world.BodySleeping(b));
}

namespace {
uint64_t g_bullet_allocations = 0;
void* CountingAlloc(size_t size) {
  ++g_bullet_allocations;
  return std::malloc(size);
}
}  // namespace

TEST_CASE("parking: steps with parked bodies and a moving hand allocate nothing",
          "[physics][parking]") {
  // Bullet allocates through its own hook (malloc), not operator new: count both.
  btAlignedAllocSetCustom(&CountingAlloc, &std::free);
  {
    PhysicsWorld world{PhysicsConfig{}};
    world.AddStaticPlane({0, 0, 1}, 0.0);
    std::vector<ph::BodyId> boxes;
    for (int i = 0; i < 10; ++i) {
      for (int j = 0; j < 10; ++j) {
        boxes.push_back(
            world.AddDynamicBox({0.3 * i, 0.3 * j + 0.6, kHalf}, {kHalf, kHalf, kHalf}, 0.5));
      }
    }
    world.AddHand(Side::kRight);
    // The palm circles 10 cm above the floor at x = y = 0, never near a box.
    auto step = [&](int i) {
      const double a = 2.0 * M_PI * i * 1e-3;
      world.hand(Side::kRight)
          ->SetTracked(TrackedHand({0.1 * std::cos(a), 0.1 * std::sin(a), 0.1}));
      world.Step();
    };
    int i = 0;
    for (; i < 3000; ++i) step(i);
    REQUIRE(world.Counters().parked_bodies == boxes.size());
    for (; i < 4000; ++i) step(i);  // the circle once round: the hand's pairs and buffers exist
    const uint64_t before = haptel::test::ThreadAllocations();
    const uint64_t bullet_before = g_bullet_allocations;
    for (; i < 6000; ++i) step(i);
    CHECK(haptel::test::ThreadAllocations() == before);
    CHECK(g_bullet_allocations == bullet_before);
    CHECK(world.Counters().parked_bodies == boxes.size());
    CHECK(world.Counters().wakings == 0);
  }
  btAlignedAllocSetCustom(nullptr, nullptr);
}
