#include "haptel/core/geometry2d.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace haptel {

Vec2 ClosestPointOnSegment(const Segment2& s, const Vec2& p) {
  const Vec2 d = s.b - s.a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0.0) return s.a;
  const double t = std::clamp((p - s.a).dot(d) / len2, 0.0, 1.0);
  return s.a + t * d;
}

std::optional<Crossing> SegmentCrossing(const Vec2& p0, const Vec2& p1, const Segment2& s) {
  const Vec2 r = p1 - p0;
  const Vec2 q = s.b - s.a;
  const double denom = Cross2(r, q);
  if (std::abs(denom) < 1e-15) return std::nullopt;
  const Vec2 w = s.a - p0;
  const double t = Cross2(w, q) / denom;
  const double u = Cross2(w, r) / denom;
  if (t < 0.0 || t > 1.0 || u < 0.0 || u > 1.0) return std::nullopt;
  return Crossing{t, u};
}

double WrapAngle(double angle_rad) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double a = std::fmod(angle_rad + std::numbers::pi, kTwoPi);
  if (a <= 0.0) a += kTwoPi;
  return a - std::numbers::pi;
}

}  // namespace haptel
