#include "haptel/physics/scene_builder.hpp"

#include <btBulletDynamicsCommon.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

#include "bullet_util.hpp"
#include "haptel/geometry/mass_properties.hpp"

namespace haptel::physics {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

/// Bullet grows a convex hull by its margin (outside the points).
constexpr double kHullMargin = 0.001;

btVector3 ToBt(const Vector3d& v) { return btVector3(v.x(), v.y(), v.z()); }

btTransform ToBt(const Matrix3d& r, const Vector3d& p) {
  const btMatrix3x3 basis(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1),
                          r(2, 2));
  return btTransform(basis, ToBt(p));
}

Pose ToPose(const Matrix3d& r, const Vector3d& p) {
  Eigen::Quaterniond q(r);
  q.normalize();
  return {{p.x(), p.y(), p.z()}, {q.w(), q.x(), q.y(), q.z()}};
}

bool IsIdentity(const Matrix3d& r, const Vector3d& p) {
  return p.norm() <= 1e-12 && (r - Matrix3d::Identity()).norm() <= 1e-12;
}

std::string Where(const SceneObject& object) {
  return "BuildScene: object '" + object.name + "': ";
}

/// One primitive in its own shape frame (not a plane).
std::unique_ptr<btCollisionShape> MakeShape(const SceneObject& object, const SceneShape& shape) {
  switch (shape.kind) {
    case ShapeKind::kBox: {
      const std::array<double, 3> h{shape.half_extents.x(), shape.half_extents.y(),
                                    shape.half_extents.z()};
      auto box = std::make_unique<btBoxShape>(ToBt(shape.half_extents));
      box->setMargin(BoxMargin(h));
      return box;
    }
    case ShapeKind::kSphere:
      return std::make_unique<btSphereShape>(shape.radius);
    case ShapeKind::kCapsule:
      return std::make_unique<btCapsuleShapeZ>(shape.radius, shape.length);
    case ShapeKind::kConvex: {
      auto hull = std::make_unique<btConvexHullShape>();
      for (const Vector3d& p : shape.points) hull->addPoint(ToBt(p), false);
      hull->recalcLocalAabb();
      hull->setMargin(kHullMargin);
      return hull;
    }
    case ShapeKind::kPlane:
      break;
  }
  throw std::invalid_argument(Where(object) + "a " + ShapeKindName(shape.kind) +
                              " cannot be part of a compound body");
}

/// The shapes, each placed by child = local⁻¹ · shape pose, as one Bullet
/// shape: the shape itself when there is one at the body frame, else a compound.
struct BuiltShape {
  std::unique_ptr<btCollisionShape> shape;
  std::vector<std::unique_ptr<btCollisionShape>> parts;
};
BuiltShape MakeBodyShape(const SceneObject& object, const std::vector<const SceneShape*>& shapes,
                         const Matrix3d& local_r, const Vector3d& local_p) {
  BuiltShape out;
  if (shapes.size() == 1) {
    const SceneShape& s = *shapes[0];
    const Matrix3d r = local_r.transpose() * s.rotation;
    const Vector3d p = local_r.transpose() * (s.position - local_p);
    if (IsIdentity(r, p)) {
      out.shape = MakeShape(object, s);
      return out;
    }
  }
  auto compound = std::make_unique<btCompoundShape>(true, static_cast<int>(shapes.size()));
  for (const SceneShape* s : shapes) {
    auto child = MakeShape(object, *s);
    const Matrix3d r = local_r.transpose() * s->rotation;
    const Vector3d p = local_r.transpose() * (s->position - local_p);
    compound->addChildShape(ToBt(r, p), child.get());
    out.parts.push_back(std::move(child));
  }
  out.shape = std::move(compound);
  return out;
}

PhysicsMaterial ToPhysics(const Material& m) { return {m.static_friction, m.restitution}; }

SceneBody BuildDynamic(PhysicsWorld& world, const SceneObject& object, std::size_t index) {
  std::vector<const SceneShape*> shapes;
  for (const SceneShape& s : object.shapes) {
    if (s.kind == ShapeKind::kPlane) {
      throw std::invalid_argument(Where(object) + "a plane on a dynamic object");
    }
    shapes.push_back(&s);
  }
  if (shapes.empty()) throw std::invalid_argument(Where(object) + "no shapes");
  const MassProperties mp = ComputeMassProperties(object);
  // Principal axes; an inertia already diagonal in the object frame keeps its
  // axes (a cube's equal moments would otherwise get arbitrary ones).
  Matrix3d axes = Matrix3d::Identity();
  Vector3d moments = mp.inertia.diagonal();
  const Matrix3d off = mp.inertia - Matrix3d(mp.inertia.diagonal().asDiagonal());
  if (off.norm() > 1e-12 * mp.inertia.trace()) {
    const PrincipalInertia principal = Diagonalize(mp.inertia);
    axes = principal.axes;
    moments = principal.moments;
  }
  SceneBody node;
  node.object = index;
  node.dynamic = true;
  node.local_position = mp.com;
  node.local_rotation = axes;
  BuiltShape built = MakeBodyShape(object, shapes, axes, mp.com);
  const Matrix3d r = object.rotation * axes;
  const Vector3d p = object.position + object.rotation * mp.com;
  node.body = world.AddRigidBody(std::move(built.shape), std::move(built.parts), mp.mass,
                                 {moments.x(), moments.y(), moments.z()}, ToPose(r, p),
                                 ToPhysics(object.material));
  return node;
}

SceneBody BuildStatic(PhysicsWorld& world, const SceneObject& object, std::size_t index) {
  std::vector<const SceneShape*> solids;
  std::vector<const SceneShape*> planes;
  for (const SceneShape& s : object.shapes) {
    (s.kind == ShapeKind::kPlane ? planes : solids).push_back(&s);
  }
  if (solids.empty() && planes.empty()) throw std::invalid_argument(Where(object) + "no shapes");
  const PhysicsMaterial material = ToPhysics(object.material);
  SceneBody node;
  node.object = index;
  node.dynamic = false;
  std::vector<BodyId> bodies;
  if (!solids.empty()) {
    BuiltShape built = MakeBodyShape(object, solids, Matrix3d::Identity(), Vector3d::Zero());
    bodies.push_back(world.AddRigidBody(std::move(built.shape), std::move(built.parts), 0.0, {},
                                        ToPose(object.rotation, object.position), material));
  }
  for (const SceneShape* s : planes) {
    if (bodies.empty()) {  // a planes-only object: its first plane's frame is the body frame
      node.local_position = s->position;
      node.local_rotation = s->rotation;
    }
    const Matrix3d r = object.rotation * s->rotation;
    const Vector3d p = object.position + object.rotation * s->position;
    bodies.push_back(world.AddRigidBody(
        std::make_unique<btStaticPlaneShape>(ToBt(s->normal.normalized()), s->offset), {}, 0.0, {},
        ToPose(r, p), material));
  }
  node.body = bodies.front();
  node.extra_bodies.assign(bodies.begin() + 1, bodies.end());
  return node;
}

}  // namespace

BuiltScene BuildScene(PhysicsWorld& world, const Scene& scene, const std::atomic<bool>* cancel) {
  BuiltScene built;
  built.order = OrderNodes(scene);
  built.nodes.reserve(built.order.objects.size());
  for (std::size_t i = 0; i < built.order.objects.size(); ++i) {
    if (cancel != nullptr && cancel->load(std::memory_order_relaxed)) {
      built.order.objects.resize(i);
      built.order.dynamic_count = std::min(built.order.dynamic_count, i);
      break;
    }
    const std::size_t index = built.order.objects[i];
    const SceneObject& object = scene.objects.at(index);
    built.nodes.push_back(i < built.order.dynamic_count ? BuildDynamic(world, object, index)
                                                        : BuildStatic(world, object, index));
  }
  return built;
}

Pose ObjectPose(const PhysicsWorld& world, const SceneBody& node) {
  const Pose body = world.BodyPose(node.body);
  const auto& q = body.orientation;
  const Matrix3d r_body =
      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  const Vector3d p_body(body.position[0], body.position[1], body.position[2]);
  const Matrix3d r = r_body * node.local_rotation.transpose();
  return ToPose(r, p_body - r * node.local_position);
}

PhysicsNeeds NeedsOf(const Scene& scene, bool physical_controls) {
  return {physical_controls, static_cast<int>(scene.objects.size())};
}

}  // namespace haptel::physics
