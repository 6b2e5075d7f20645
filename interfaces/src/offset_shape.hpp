#pragma once
// A hand offset past a dead zone as a signed fraction of full scale, and its
// inverse: how the gesture interfaces turn hand positions into commands.
#include <algorithm>
#include <cmath>

namespace haptel::interfaces::detail {

/// Offset past the dead zone as a fraction of full scale, signed, in [-1, 1].
inline double Shape(double offset, double dead_zone, double full_scale) {
  const double past = std::max(0.0, std::abs(offset) - dead_zone);
  return std::copysign(std::min(1.0, past / full_scale), offset);
}

/// Inverse of Shape for a fraction in [-1, 1].
inline double Unshape(double fraction, double dead_zone, double full_scale) {
  if (fraction == 0.0) return 0.0;
  const double f = std::clamp(fraction, -1.0, 1.0);
  return std::copysign(dead_zone + std::abs(f) * full_scale, f);
}

}  // namespace haptel::interfaces::detail
