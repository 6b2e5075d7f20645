#pragma once
/// @file Small helpers on the plain haptics types, shared by physics tests and
/// benchmarks (not for the servo loop, which works on its own data).
#include <array>
#include <cmath>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

inline double Norm(const Vec3d& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

inline double Distance(const Vec3d& a, const Vec3d& b) {
  return Norm({a[0] - b[0], a[1] - b[1], a[2] - b[2]});
}

/// Quaternion (w, x, y, z) of a rotation by `angle` (rad) about a unit `axis`.
inline std::array<double, 4> AxisAngle(const Vec3d& axis, double angle) {
  const double s = std::sin(0.5 * angle);
  return {std::cos(0.5 * angle), axis[0] * s, axis[1] * s, axis[2] * s};
}

/// A valid tracked hand at `wrist` (m) with orientation `q` (w, x, y, z).
inline HandSample TrackedHand(const Vec3d& wrist, const std::array<double, 4>& q = {1, 0, 0, 0}) {
  HandSample s;
  s.valid = true;
  s.position = wrist;
  s.orientation = q;
  return s;
}

}  // namespace haptel::haptics
