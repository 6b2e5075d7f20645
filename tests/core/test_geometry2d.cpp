// Planar geometry: closest point on a segment, segment crossing, angle wrap.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/core/geometry2d.hpp"

using haptel::Segment2;
using haptel::Vec2;

namespace {
constexpr double kPi = std::numbers::pi;
constexpr double kEps = 1e-12;

bool Near(const Vec2& a, const Vec2& b, double eps = 1e-9) { return (a - b).norm() <= eps; }
}  // namespace

TEST_CASE("ClosestPointOnSegment: interior projection", "[geometry]") {
  const Segment2 s{Vec2(1.0, 1.0), Vec2(5.0, 1.0)};
  const Vec2 p(3.5, 4.0);
  const Vec2 q = haptel::ClosestPointOnSegment(s, p);
  CHECK(Near(q, Vec2(3.5, 1.0)));
  // The offset to the closest interior point is perpendicular to the segment.
  CHECK(std::abs((p - q).dot(s.b - s.a)) < 1e-9);

  // A slanted segment: the foot of the perpendicular.
  const Segment2 d{Vec2(0.0, 0.0), Vec2(2.0, 2.0)};
  const Vec2 r = haptel::ClosestPointOnSegment(d, Vec2(0.0, 2.0));
  CHECK(Near(r, Vec2(1.0, 1.0)));
  // A point on the segment is its own closest point.
  CHECK(Near(haptel::ClosestPointOnSegment(d, Vec2(0.5, 0.5)), Vec2(0.5, 0.5)));
}

TEST_CASE("ClosestPointOnSegment: clamps to the endpoints", "[geometry]") {
  const Segment2 s{Vec2(1.0, 1.0), Vec2(5.0, 1.0)};
  CHECK(Near(haptel::ClosestPointOnSegment(s, Vec2(-3.0, 2.0)), s.a));
  CHECK(Near(haptel::ClosestPointOnSegment(s, Vec2(9.0, -7.0)), s.b));
  CHECK(Near(haptel::ClosestPointOnSegment(s, s.a), s.a));
  CHECK(Near(haptel::ClosestPointOnSegment(s, s.b), s.b));
  // Reversing the segment does not change the answer.
  const Segment2 r{s.b, s.a};
  CHECK(Near(haptel::ClosestPointOnSegment(r, Vec2(-3.0, 2.0)), s.a));
  CHECK(Near(haptel::ClosestPointOnSegment(r, Vec2(2.0, 8.0)), Vec2(2.0, 1.0)));
}

TEST_CASE("ClosestPointOnSegment: a degenerate segment is a point", "[geometry]") {
  const Segment2 s{Vec2(2.0, -1.0), Vec2(2.0, -1.0)};
  const Vec2 q = haptel::ClosestPointOnSegment(s, Vec2(10.0, 10.0));
  CHECK(std::isfinite(q.x()));
  CHECK(std::isfinite(q.y()));
  CHECK(Near(q, Vec2(2.0, -1.0)));
}

TEST_CASE("SegmentCrossing: crossing motion gives t and u", "[geometry]") {
  // Motion from (0,-1) to (0,3) crosses the segment (-2,0)->(2,0) at (0,0).
  const Segment2 s{Vec2(-2.0, 0.0), Vec2(2.0, 0.0)};
  const auto c = haptel::SegmentCrossing(Vec2(0.0, -1.0), Vec2(0.0, 3.0), s);
  REQUIRE(c.has_value());
  CHECK(c->t == Approx(0.25));
  CHECK(c->u == Approx(0.5));

  // An oblique case: check the parameters reproduce the same point on both.
  const Vec2 p0(1.0, 4.0);
  const Vec2 p1(3.0, -2.0);
  const Segment2 s2{Vec2(0.0, 0.0), Vec2(4.0, 2.0)};
  const auto c2 = haptel::SegmentCrossing(p0, p1, s2);
  REQUIRE(c2.has_value());
  CHECK(c2->t > 0.0);
  CHECK(c2->t < 1.0);
  CHECK(c2->u > 0.0);
  CHECK(c2->u < 1.0);
  const Vec2 on_motion = p0 + c2->t * (p1 - p0);
  const Vec2 on_segment = s2.a + c2->u * (s2.b - s2.a);
  CHECK(Near(on_motion, on_segment));

  // The direction of the motion does not matter for crossing, only for t.
  const auto back = haptel::SegmentCrossing(p1, p0, s2);
  REQUIRE(back.has_value());
  CHECK(back->t == Approx(1.0 - c2->t));
  CHECK(back->u == Approx(c2->u));
}

TEST_CASE("SegmentCrossing: touching at an end counts", "[geometry]") {
  const Segment2 s{Vec2(-1.0, 0.0), Vec2(1.0, 0.0)};
  // Motion ends exactly on the segment.
  const auto end_on = haptel::SegmentCrossing(Vec2(0.5, 2.0), Vec2(0.5, 0.0), s);
  REQUIRE(end_on.has_value());
  CHECK(end_on->t == Approx(1.0));
  CHECK(end_on->u == Approx(0.75));
  // Motion passes through the segment's endpoint.
  const auto through_end = haptel::SegmentCrossing(Vec2(1.0, -1.0), Vec2(1.0, 1.0), s);
  REQUIRE(through_end.has_value());
  CHECK(through_end->t == Approx(0.5));
  CHECK(through_end->u == Approx(1.0));
  // Motion starts on the segment.
  const auto start_on = haptel::SegmentCrossing(Vec2(-1.0, 0.0), Vec2(-1.0, 5.0), s);
  REQUIRE(start_on.has_value());
  CHECK(std::abs(start_on->t) < kEps);
  CHECK(std::abs(start_on->u) < kEps);
}

TEST_CASE("SegmentCrossing: parallel and collinear motion does not cross", "[geometry]") {
  const Segment2 s{Vec2(0.0, 0.0), Vec2(4.0, 0.0)};
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(0.0, 1.0), Vec2(4.0, 1.0), s).has_value());
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(1.0, 0.0), Vec2(3.0, 0.0), s).has_value());
  // Zero-length motion has no direction: nothing crosses.
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(1.0, 0.0), Vec2(1.0, 0.0), s).has_value());
}

TEST_CASE("SegmentCrossing: misses", "[geometry]") {
  const Segment2 s{Vec2(-1.0, 0.0), Vec2(1.0, 0.0)};
  // Stops short of the segment.
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(0.0, 2.0), Vec2(0.0, 0.5), s).has_value());
  // Would cross the segment's line, but beyond its end.
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(2.0, -1.0), Vec2(2.0, 1.0), s).has_value());
  // Starts past the segment and moves away.
  CHECK_FALSE(haptel::SegmentCrossing(Vec2(0.0, -0.5), Vec2(0.0, -3.0), s).has_value());
}

TEST_CASE("WrapAngle: maps to (-pi, pi]", "[geometry]") {
  CHECK(std::abs(haptel::WrapAngle(0.0)) < kEps);
  CHECK(haptel::WrapAngle(1.0) == Approx(1.0));
  CHECK(haptel::WrapAngle(-1.0) == Approx(-1.0));
  CHECK(haptel::WrapAngle(kPi / 2 + 2 * kPi) == Approx(kPi / 2));
  CHECK(haptel::WrapAngle(-kPi / 2 - 6 * kPi) == Approx(-kPi / 2));
  CHECK(haptel::WrapAngle(3 * kPi / 2) == Approx(-kPi / 2));
  CHECK(haptel::WrapAngle(-3 * kPi / 2) == Approx(kPi / 2));
  // The interval is half-open: pi stays pi, -pi becomes pi.
  CHECK(haptel::WrapAngle(kPi) == Approx(kPi));
  CHECK(haptel::WrapAngle(-kPi) == Approx(kPi));

  for (double a = -50.0; a <= 50.0; a += 0.37) {
    const double w = haptel::WrapAngle(a);
    CHECK(w > -kPi);
    CHECK(w <= kPi);
    // Same direction as the input.
    CHECK(std::cos(w) == Approx(std::cos(a)).margin(1e-9));
    CHECK(std::sin(w) == Approx(std::sin(a)).margin(1e-9));
  }
}
