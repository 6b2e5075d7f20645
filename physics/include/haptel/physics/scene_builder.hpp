#pragma once
/// @file Builds a haptic scene (config/scene.hpp) into a PhysicsWorld: one
/// Bullet body per scene object, created in node order (dynamic objects
/// first, static ones last: OrderNodes), with handles so the view can read the
/// objects' poses back (SyncPoses over BuiltScene::nodes).
///
/// - Dynamic object: mass, centre of mass and inertia from its shapes
///   (ComputeMassProperties). The body frame sits at the centre of mass along
///   the principal axes (Diagonalize), so Bullet gets a diagonal inertia;
///   several shapes, or one shape off that frame, become a btCompoundShape
///   whose children are placed relative to it.
/// - Static object: mass 0, body frame = object frame. Each plane becomes a
///   btStaticPlaneShape body of its own (an infinite shape does not belong in a
///   compound); the other shapes form one body (a compound when needed).
/// - Shapes: box → btBoxShape (margin inside, as the world's own boxes),
///   sphere → btSphereShape, capsule → btCapsuleShapeZ, convex →
///   btConvexHullShape of its points with a 1 mm margin (Bullet grows a hull by
///   its margin; the default 4 cm would float objects visibly).
/// - Material: Bullet has one friction coefficient for sticking and sliding;
///   the scene's static friction is used (what holds a grasped or resting
///   object), and its restitution. Pairs combine by the average (PhysicsWorld).
#include <Eigen/Core>
#include <atomic>
#include <cstddef>
#include <vector>

#include "haptel/config/scene.hpp"
#include "haptel/physics/world.hpp"

namespace haptel::physics {

/// One scene object in the world: a node of the haptic scene.
struct SceneBody {
  std::size_t object = 0;  ///< index into Scene::objects
  bool dynamic = false;
  BodyId body = -1;  ///< the object's body (a static object made only of planes: its first plane)
  std::vector<BodyId> extra_bodies;  ///< a static object's further bodies (its other planes)
  /// The body frame in the object frame: body = object · [local_rotation | local_position]
  /// (a dynamic object: centre of mass and principal axes; static: identity).
  Eigen::Vector3d local_position = Eigen::Vector3d::Zero();
  Eigen::Matrix3d local_rotation = Eigen::Matrix3d::Identity();
};

struct BuiltScene {
  SceneNodeOrder order;
  std::vector<SceneBody> nodes;  ///< in node order: nodes[i].object == order.objects[i]
};

/// Creates the scene's bodies in `world` (before Start). Throws
/// std::invalid_argument for an object the world cannot build (e.g. a plane on
/// a dynamic object); the world keeps any bodies made before the error.
/// Once `*cancel` is set (a run interrupted while thousands of bodies are
/// added, each meeting every body it overlaps), no further object is built:
/// the scene returned holds the nodes built so far (its order cut to match).
BuiltScene BuildScene(PhysicsWorld& world, const Scene& scene,
                      const std::atomic<bool>* cancel = nullptr);

/// The pose of the object frame in the world (what the scene file's
/// position/rotation describe), from its body's current pose.
Pose ObjectPose(const PhysicsWorld& world, const SceneBody& node);

/// What a scene asks of physics: every object is a touchable body.
PhysicsNeeds NeedsOf(const Scene& scene, bool physical_controls = false);

}  // namespace haptel::physics
