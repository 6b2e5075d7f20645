#pragma once
// Small helpers between Bullet and Haptel's plain types. Private to the
// physics library.
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "haptel/physics/proxy_hand.hpp"

namespace haptel::physics {

inline btVector3 ToBt(const Vec3d& v) { return btVector3(v[0], v[1], v[2]); }
inline Vec3d ToVec(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

inline Pose ToPose(const btTransform& t) {
  const btQuaternion q = t.getRotation();
  return {ToVec(t.getOrigin()), {q.w(), q.x(), q.y(), q.z()}};
}

/// Bullet keeps a box's collision margin inside its extents; its default
/// (4 cm) is larger than a palm is thick, so small boxes get a small one.
inline double BoxMargin(const std::array<double, 3>& half_extents) {
  const double smallest = std::min({half_extents[0], half_extents[1], half_extents[2]});
  return std::min(0.004, 0.2 * smallest);
}

/// Friction, restitution, rolling and spinning friction of `material` on
/// `body` (Bullet reads them when a contact point is created).
inline void SetMaterial(btCollisionObject& body, const PhysicsMaterial& material) {
  body.setFriction(material.friction);
  body.setRestitution(material.restitution);
  body.setRollingFriction(material.rolling_friction);
  body.setSpinningFriction(material.spinning_friction);
}

inline bool IsFinite(const btVector3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

/// True when the body's pose and velocities are all finite.
inline bool IsFinite(const btRigidBody& body) {
  const btTransform& t = body.getWorldTransform();
  const btMatrix3x3& b = t.getBasis();
  return IsFinite(t.getOrigin()) && IsFinite(b[0]) && IsFinite(b[1]) && IsFinite(b[2]) &&
         IsFinite(body.getLinearVelocity()) && IsFinite(body.getAngularVelocity());
}

/// Drops the cached contacts of a body that was teleported (or held NaN) and
/// refreshes its bounding box in the broadphase.
inline void ForgetContacts(btDiscreteDynamicsWorld& world, btRigidBody& body) {
  if (body.getBroadphaseHandle() == nullptr) return;
  world.getBroadphase()->getOverlappingPairCache()->cleanProxyFromPairs(body.getBroadphaseHandle(),
                                                                        world.getDispatcher());
  world.updateSingleAabb(&body);
}

}  // namespace haptel::physics
