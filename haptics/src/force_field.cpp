#include "haptel/haptics/force_field.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace haptel::haptics {

namespace {
Eigen::Map<const Eigen::Vector3d> View(const Vec3d& v) {
  return Eigen::Map<const Eigen::Vector3d>(v.data());
}
}  // namespace

Vec3d EvaluateForceField(const ForceField& field, const Vec3d& position, const Vec3d& velocity) {
  Vec3d out{};
  if (!field.enabled) return out;
  const Eigen::Vector3d p = View(position);
  const Eigen::Vector3d v = View(velocity);
  const Eigen::Vector3d d = p - View(field.neutral);
  Eigen::Vector3d f =
      -(field.stiffness + field.stiffness_growth * d.norm()) * d - field.damping * v;
  if (field.wall_active) {
    const Eigen::Vector3d n = View(field.wall_normal);
    const double penetration = (p - View(field.wall_point)).dot(n);
    if (penetration > 0.0) {
      const double approach = std::max(0.0, v.dot(n));
      f -= (field.wall_stiffness * penetration + field.wall_damping * approach) * n;
    }
  }
  if (field.guidance_active) {
    const Eigen::Vector3d n = View(field.guidance_normal);
    const double penetration = (p - View(field.guidance_point)).dot(n);
    if (penetration > 0.0)
      f -= std::min(field.guidance_stiffness * penetration, field.guidance_max_force) * n;
  }
  Eigen::Map<Eigen::Vector3d>(out.data()) = f;
  return out;
}

bool LimitForce(Vec3d& force, double limit) {
  const double norm2 = force[0] * force[0] + force[1] * force[1] + force[2] * force[2];
  if (!std::isfinite(norm2)) {
    force = Vec3d{};
    return true;
  }
  if (norm2 <= limit * limit) return false;
  const double scale = limit / std::sqrt(norm2);
  for (double& c : force) c *= scale;
  return true;
}

}  // namespace haptel::haptics
