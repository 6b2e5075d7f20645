// Building the haptic scene into the physics world: the shipped table scene in
// both formats, node order, settling and sleep, compound bodies at the centre
// of mass, what a scene asks of physics.
#include <btBulletDynamicsCommon.h>

#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <span>
#include <stdexcept>
#include <vector>

#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/geometry/mass_properties.hpp"
#include "haptel/physics/scene_builder.hpp"
#include "haptel/physics/world.hpp"

namespace {

using haptel::PhysicsConfig;
using haptel::Scene;
using haptel::SceneObject;
using haptel::SceneShape;
using haptel::ShapeKind;
using haptel::physics::PhysicsWorld;
namespace ph = haptel::physics;

Eigen::Vector3d Position(const ph::Pose& p) {
  return {p.position[0], p.position[1], p.position[2]};
}
Eigen::Quaterniond Rotation(const ph::Pose& p) {
  const auto& q = p.orientation;
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}
double AngleBetween(const ph::Pose& a, const ph::Pose& b) {
  return Rotation(a).angularDistance(Rotation(b));
}

const ph::SceneBody& Node(const Scene& scene, const ph::BuiltScene& built, const char* name) {
  for (const ph::SceneBody& n : built.nodes) {
    if (scene.objects[n.object].name == name) return n;
  }
  throw std::runtime_error(std::string("no node ") + name);
}

void StepFor(PhysicsWorld& world, double seconds) {
  const int steps = static_cast<int>(std::lround(seconds / world.config().step_s));
  for (int i = 0; i < steps; ++i) world.Step();
}

/// Builds `scene`, steps 2 s, and checks the table's box settled on the top.
ph::Pose SettleBox(const Scene& scene) {
  PhysicsWorld world{PhysicsConfig{}};
  const ph::BuiltScene built = ph::BuildScene(world, scene);
  REQUIRE(built.nodes.size() == scene.objects.size());
  const ph::SceneBody& box = Node(scene, built, "box");
  // Before any step the body gives back the object's pose from the file.
  const SceneObject& object = scene.objects[box.object];
  const ph::Pose start = ph::ObjectPose(world, box);
  CHECK((Position(start) - object.position).norm() < 1e-12);
  CHECK((Rotation(start).toRotationMatrix() - object.rotation).norm() < 1e-6);

  StepFor(world, 2.0);
  const ph::Pose settled = ph::ObjectPose(world, box);
  INFO("box at " << Position(settled).transpose());
  // The top's upper face is at 0.75 m; the 10 cm box's centre 5 cm above it.
  CHECK(settled.position[2] == Approx(0.80).margin(0.003));
  CHECK(std::hypot(settled.position[0] - 0.1, settled.position[1]) < 0.003);
  // Bullet puts a body to sleep after 2 s below its thresholds
  // (gDeactivationTime): the box, put down at rest, has been still since the
  // first step and falls asleep within a few steps more.
  int extra_steps = 0;
  while (!world.BodySleeping(box.body) && extra_steps < 100) {
    world.Step();
    ++extra_steps;
  }
  INFO("asleep after 2 s + " << extra_steps << " steps");
  CHECK(extra_steps < 100);
  CHECK(world.BodySleeping(box.body));
  CHECK(world.BodyVelocity(box.body) == ph::Vec3d{0.0, 0.0, 0.0});
  // It stays upright, turned 30° about z as it was put down.
  CHECK(AngleBetween(settled, start) < 0.01);
  // Static bodies never moved.
  const ph::SceneBody& table = Node(scene, built, "table");
  CHECK((Position(ph::ObjectPose(world, table))).norm() < 1e-12);
  CHECK(world.Counters().body_resets == 0);
  return settled;
}

SceneObject DynamicObject(std::vector<SceneShape> shapes, double mass) {
  SceneObject o;
  o.name = "thing";
  o.dynamic = true;
  o.mass = mass;
  o.shapes = std::move(shapes);
  return o;
}

SceneShape Box(const Eigen::Vector3d& half, const Eigen::Vector3d& at) {
  SceneShape s;
  s.kind = ShapeKind::kBox;
  s.half_extents = half;
  s.position = at;
  return s;
}

}  // namespace

TEST_CASE("scene builder: the shipped table scene, YAML and XML, settles the box on the top",
          "[physics][scene]") {
  const Scene yaml = haptel::LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  const Scene xml = haptel::ImportMhapticXml(haptel::ShippedFile("config/scenes/table.xml"));
  const ph::Pose from_yaml = SettleBox(yaml);
  const ph::Pose from_xml = SettleBox(xml);
  // The same scene in two formats: the same settled pose (the XML's rotation
  // is printed to 7 digits, hence not bit-identical).
  CHECK((Position(from_yaml) - Position(from_xml)).norm() < 1e-4);
  CHECK(AngleBetween(from_yaml, from_xml) < 1e-4);
}

TEST_CASE("scene builder: nodes in node order, dynamic first; poses sync up to the first static",
          "[physics][scene]") {
  const Scene scene = haptel::LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  PhysicsWorld world{PhysicsConfig{}};
  const ph::BuiltScene built = ph::BuildScene(world, scene);
  REQUIRE(built.order.dynamic_count == 1);
  REQUIRE(built.nodes.size() == 3);
  CHECK(scene.objects[built.nodes[0].object].name == "box");
  CHECK(built.nodes[0].dynamic);
  CHECK_FALSE(built.nodes[1].dynamic);
  CHECK_FALSE(built.nodes[2].dynamic);
  for (std::size_t i = 0; i < built.nodes.size(); ++i) {
    CHECK(built.nodes[i].object == built.order.objects[i]);
  }
  // Dynamic bodies were inserted into the world first.
  CHECK(built.nodes[0].body == 0);
  CHECK(world.body(built.nodes[0].body).getInvMass() == Approx(1.0 / 0.5));
  CHECK(world.body(built.nodes[1].body).isStaticObject());
  CHECK(world.body(built.nodes[2].body).isStaticObject());
  // The floor is a Bullet plane; the table's top and legs one compound.
  CHECK(world.body(Node(scene, built, "floor").body).getCollisionShape()->getShapeType() ==
        STATIC_PLANE_PROXYTYPE);
  const btCollisionShape* table = world.body(Node(scene, built, "table").body).getCollisionShape();
  REQUIRE(table->getShapeType() == COMPOUND_SHAPE_PROXYTYPE);
  CHECK(static_cast<const btCompoundShape*>(table)->getNumChildShapes() == 5);
  // Material: static friction and restitution of the file (wood).
  CHECK(world.body(Node(scene, built, "table").body).getFriction() ==
        Approx(scene.objects[Node(scene, built, "table").object].material.static_friction));

  std::vector<ph::SceneBody> nodes = built.nodes;
  std::vector<ph::Pose> synced;
  const std::size_t n = haptel::SyncPoses(
      std::span<ph::SceneBody>(nodes), [](const ph::SceneBody& node) { return node.dynamic; },
      [&](const ph::SceneBody& node) { synced.push_back(ph::ObjectPose(world, node)); });
  CHECK(n == 1);
  REQUIRE(synced.size() == 1);
  CHECK(synced[0].position[2] == Approx(0.8));
}

TEST_CASE("scene builder: a compound body sits at its centre of mass, along its principal axes",
          "[physics][scene]") {
  // An L of two boxes, turned and lifted: its centre of mass is off both boxes'
  // centres and its inertia is not diagonal in the object frame.
  SceneObject l = DynamicObject(
      {Box({0.1, 0.02, 0.02}, {0.0, 0.0, 0.0}), Box({0.02, 0.06, 0.02}, {0.08, 0.08, 0.0})}, 1.2);
  l.position = {0.3, -0.2, 1.0};
  l.rotation = Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  SceneShape hull;
  hull.kind = ShapeKind::kConvex;
  hull.points = {{0, 0, 0}, {0.1, 0, 0}, {0, 0.1, 0}, {0, 0, 0.1}, {0.02, 0.02, 0.02}};
  SceneObject tetra = DynamicObject({hull}, 0.3);
  tetra.name = "tetra";
  tetra.position = {-1.0, 0.0, 0.5};
  Scene scene;
  scene.objects = {l, tetra};

  PhysicsConfig config;
  config.gravity = {0.0, 0.0, 0.0};
  PhysicsWorld world{config};
  const ph::BuiltScene built = ph::BuildScene(world, scene);
  REQUIRE(built.nodes.size() == 2);
  const ph::SceneBody& node = built.nodes[0];
  btRigidBody& body = world.body(node.body);
  REQUIRE(body.getCollisionShape()->getShapeType() == COMPOUND_SHAPE_PROXYTYPE);

  const haptel::MassProperties mp = haptel::ComputeMassProperties(l);
  CHECK(node.local_position.isApprox(mp.com, 1e-12));
  CHECK(1.0 / body.getInvMass() == Approx(1.2));
  // Body frame: the world centre of mass, and the inertia diagonal in it.
  const ph::Pose pose = world.BodyPose(node.body);
  CHECK((Position(pose) - (l.position + l.rotation * mp.com)).norm() < 1e-12);
  const Eigen::Matrix3d axes = l.rotation.transpose() * Rotation(pose).toRotationMatrix();
  const Eigen::Matrix3d in_body = axes.transpose() * mp.inertia * axes;
  CHECK((in_body - Eigen::Matrix3d(in_body.diagonal().asDiagonal())).norm() <
        1e-9 * in_body.trace());
  const btVector3 inv = body.getInvInertiaDiagLocal();
  CHECK(1.0 / inv.x() == Approx(in_body(0, 0)));
  CHECK(1.0 / inv.y() == Approx(in_body(1, 1)));
  CHECK(1.0 / inv.z() == Approx(in_body(2, 2)));
  // The object frame comes back exactly from the body frame.
  const ph::Pose object = ph::ObjectPose(world, node);
  CHECK((Position(object) - l.position).norm() < 1e-12);
  CHECK((Rotation(object).toRotationMatrix() - l.rotation).norm() < 1e-9);
  // A spin about the centre of mass, without gravity, keeps the centre in place.
  body.setAngularVelocity(btVector3(1.0, -2.0, 0.5));
  StepFor(world, 0.5);
  CHECK((Position(world.BodyPose(node.body)) - Position(pose)).norm() < 1e-9);
  // The hull, off its centre of mass, is a Bullet hull inside a compound.
  const btCollisionShape* t = world.body(built.nodes[1].body).getCollisionShape();
  REQUIRE(t->getShapeType() == COMPOUND_SHAPE_PROXYTYPE);
  CHECK(static_cast<const btCompoundShape*>(t)->getChildShape(0)->getShapeType() ==
        CONVEX_HULL_SHAPE_PROXYTYPE);
}

TEST_CASE("scene builder: a plane on a dynamic object is refused", "[physics][scene]") {
  SceneShape plane;
  plane.kind = ShapeKind::kPlane;
  Scene scene;
  scene.objects = {DynamicObject({Box({0.1, 0.1, 0.1}, {0, 0, 0}), plane}, 1.0)};
  PhysicsWorld world{PhysicsConfig{}};
  CHECK_THROWS_AS(ph::BuildScene(world, scene), std::invalid_argument);
}

TEST_CASE("scene builder: what a scene asks of physics", "[physics][scene]") {
  const Scene table = haptel::LoadScene(haptel::ShippedFile("config/scenes/table.yaml"));
  CHECK(ph::NeedsOf(table).scene_bodies == 3);
  CHECK(ph::NeedsWorld(ph::NeedsOf(table)));
  CHECK_FALSE(ph::NeedsWorld(ph::NeedsOf(Scene{})));
  CHECK(ph::NeedsWorld(ph::NeedsOf(Scene{}, true)));
}
