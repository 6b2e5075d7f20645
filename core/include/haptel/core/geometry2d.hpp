#pragma once
/// @file Planar geometry shared by track timing and the vehicle simulator.
#include <Eigen/Core>
#include <numbers>
#include <optional>

namespace haptel {

using Vec2 = Eigen::Vector2d;

/// A line segment from a to b.
struct Segment2 {
  Vec2 a;
  Vec2 b;
};

/// Closest point on segment s to p.
Vec2 ClosestPointOnSegment(const Segment2& s, const Vec2& p);

/// Parameters (t on p0->p1, u on s.a->s.b), both in [0,1], where the motion
/// p0->p1 crosses segment s; nullopt if it does not (parallel counts as not).
struct Crossing {
  double t;
  double u;
};
std::optional<Crossing> SegmentCrossing(const Vec2& p0, const Vec2& p1, const Segment2& s);

/// 2-D cross product (z of the 3-D cross product).
inline double Cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Degrees to radians.
constexpr double Radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

/// Wraps an angle to (-pi, pi].
double WrapAngle(double angle_rad);

}  // namespace haptel
