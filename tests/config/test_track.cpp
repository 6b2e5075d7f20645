// Track geometry derived from the shipped track files: arc length, walls,
// gates, posts and the start. Expected values are computed here from the
// centre line, independently of Track's own bookkeeping.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/core/geometry2d.hpp"

using haptel::Segment2;
using haptel::Track;
using haptel::Vec2;

namespace {

constexpr double kTol = 1e-9;

double DistanceToSegment(const Segment2& s, const Vec2& p) {
  return (haptel::ClosestPointOnSegment(s, p) - p).norm();
}

double NearestWallDistance(const Track& track, const Vec2& p, const Segment2** nearest = nullptr) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& w : track.walls()) {
    const double d = DistanceToSegment(w, p);
    if (d < best) {
      best = d;
      if (nearest != nullptr) *nearest = &w;
    }
  }
  return best;
}

// Centre-line segment i (closing segment included).
Segment2 CentreSegment(const haptel::TrackConfig& c, size_t i) {
  return {c.centerline[i], c.centerline[(i + 1) % c.centerline.size()]};
}

Vec2 LeftNormal(const Vec2& d) { return Vec2(-d.y(), d.x()).normalized(); }

}  // namespace

TEST_CASE("Track geometry of the shipped tracks", "[track]") {
  const std::string file =
      GENERATE(as<std::string>{}, "config/tracks/test-short.yaml", "config/tracks/grand-prix.yaml");
  INFO("track " << file);
  const haptel::TrackConfig config = haptel::LoadTrack(file);
  const Track track(config);
  const auto& c = config.centerline;
  const size_t n = c.size();
  REQUIRE(n >= 3);
  const double h = config.corridor_width / 2;

  // Arc length at each vertex, summed here from the points.
  std::vector<double> at(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) at[i + 1] = at[i] + (c[(i + 1) % n] - c[i]).norm();
  const double length = at[n];

  SECTION("length is the sum of the centre-line segments, closing one included") {
    CHECK(track.length() == Approx(length).epsilon(1e-12));
  }

  SECTION("PointAt walks the centre line and wraps") {
    CHECK((track.PointAt(0.0) - c[0]).norm() < kTol);
    CHECK((track.PointAt(track.length()) - c[0]).norm() < kTol);
    CHECK((track.PointAt(-track.length()) - c[0]).norm() < kTol);
    for (size_t i = 0; i < n; ++i) {
      INFO("vertex " << i);
      const Vec2 mid = 0.5 * (c[i] + c[(i + 1) % n]);
      CHECK((track.PointAt(0.5 * (at[i] + at[i + 1])) - mid).norm() < kTol);
      // Vertices sit at their arc length, also one lap on or one lap back.
      CHECK((track.PointAt(at[i]) - c[i]).norm() < kTol);
      CHECK((track.PointAt(at[i] + length) - c[i]).norm() < 1e-6);
      CHECK((track.PointAt(at[i] - length) - c[i]).norm() < 1e-6);
    }
  }

  SECTION("TangentAt is the unit direction of the segment") {
    const Vec2 first = (c[1] - c[0]).normalized();
    CHECK((track.TangentAt(0.0) - first).norm() < kTol);
    CHECK((track.TangentAt(0.5 * at[1]) - first).norm() < kTol);
    for (size_t i = 0; i < n; ++i) {
      INFO("segment " << i);
      const Vec2 t = track.TangentAt(0.5 * (at[i] + at[i + 1]));
      CHECK(t.norm() == Approx(1.0));
      CHECK((t - (c[(i + 1) % n] - c[i]).normalized()).norm() < kTol);
    }
    // Just before the end of the lap: the closing segment.
    CHECK((track.TangentAt(length - 1e-3) - (c[0] - c[n - 1]).normalized()).norm() < kTol);
  }

  SECTION("ClosestArcLength inverts PointAt") {
    for (double f : {0.013, 0.1, 0.27, 0.5, 0.61, 0.77, 0.93, 0.995}) {
      const double s = f * length;
      INFO("s = " << s);
      CHECK(track.ClosestArcLength(track.PointAt(s)) == Approx(s).margin(1e-9));
    }
    // A point pushed sideways from the middle of a segment maps back to it
    // (near a corner the inside offset may be closer to the next segment).
    for (size_t i = 0; i < n; ++i) {
      const double s = 0.5 * (at[i] + at[i + 1]);
      INFO("middle of segment " << i);
      const Vec2 side = 0.1 * h * LeftNormal(track.TangentAt(s));
      CHECK(track.ClosestArcLength(track.PointAt(s) + side) == Approx(s).margin(1e-9));
      CHECK(track.ClosestArcLength(track.PointAt(s) - side) == Approx(s).margin(1e-9));
    }
  }

  SECTION("walls run parallel to the centre line at half the corridor width") {
    // Two walls per centre-line segment.
    CHECK(track.walls().size() == 2 * n);
    for (size_t i = 0; i < n; ++i) {
      INFO("segment " << i);
      const Segment2 seg = CentreSegment(config, i);
      const Vec2 mid = 0.5 * (seg.a + seg.b);
      const Vec2 dir = (seg.b - seg.a).normalized();
      // No wall is nearer the middle of a segment than half the corridor.
      CHECK(NearestWallDistance(track, mid) == Approx(h).epsilon(1e-9));
      // One wall on each side runs parallel to the segment (same direction),
      // both its ends h from the segment's line: signed distance +h left, -h right.
      int left_walls = 0;
      int right_walls = 0;
      for (const auto& w : track.walls()) {
        const Vec2 wd = w.b - w.a;
        if (wd.norm() < 1e-12) continue;
        if (std::abs(haptel::Cross2(wd.normalized(), dir)) > 1e-9 || wd.dot(dir) <= 0.0) continue;
        const double da = haptel::Cross2(dir, w.a - seg.a);
        const double db = haptel::Cross2(dir, w.b - seg.a);
        if (std::abs(da - h) < 1e-9 && std::abs(db - h) < 1e-9) ++left_walls;
        if (std::abs(da + h) < 1e-9 && std::abs(db + h) < 1e-9) ++right_walls;
      }
      CHECK(left_walls >= 1);
      CHECK(right_walls >= 1);
      // Where the segment is long enough to clear the corners' mitres, its
      // middle has a wall exactly h away on both sides.
      if ((seg.b - seg.a).norm() > 2.5 * config.corridor_width) {
        const Vec2 left = LeftNormal(dir);
        CHECK(NearestWallDistance(track, mid + h * left) < 1e-9);
        CHECK(NearestWallDistance(track, mid - h * left) < 1e-9);
      }
    }
  }

  SECTION("gates: posts a gate width apart, symmetric about the centre line") {
    REQUIRE(track.gates().size() == config.gates.size());
    for (size_t k = 0; k < config.gates.size(); ++k) {
      INFO("gate " << k);
      const haptel::Gate& g = track.gates()[k];
      const haptel::GateSpec& spec = config.gates[k];
      CHECK(g.along == spec.along);
      // The gate's centre is on the centre line at its distance.
      CHECK(track.ClosestArcLength(g.center) == Approx(spec.along).margin(1e-9));
      CHECK(track.ClosestArcLength(g.center) > 0.0);
      CHECK((g.left_post - g.right_post).norm() == Approx(spec.width));
      // Symmetric: the centre is halfway, and the posts lie across the track.
      CHECK((0.5 * (g.left_post + g.right_post) - g.center).norm() < kTol);
      CHECK(std::abs((g.left_post - g.right_post).dot(g.tangent)) < kTol);
      CHECK(g.tangent.norm() == Approx(1.0));
      CHECK(haptel::Cross2(g.tangent, g.left_post - g.center) > 0.0);  // left is left
      // Posts are inside the corridor.
      CHECK(NearestWallDistance(track, g.left_post) > config.post_radius);
      CHECK(NearestWallDistance(track, g.right_post) > config.post_radius);
      // The gate line passes through both posts ...
      CHECK(DistanceToSegment(g.line, g.left_post) < kTol);
      CHECK(DistanceToSegment(g.line, g.right_post) < kTol);
      // ... spans the corridor from wall to wall ...
      CHECK((g.line.b - g.line.a).norm() >= config.corridor_width);
      CHECK(NearestWallDistance(track, 0.5 * (g.line.a + g.line.b)) == Approx(h).margin(1e-9));
      // ... and crosses the centre line where the gate is.
      bool crossed = false;
      for (size_t i = 0; i < n; ++i) {
        const Segment2 seg = CentreSegment(config, i);
        if (auto x = haptel::SegmentCrossing(g.line.a, g.line.b, seg)) {
          const Vec2 p = seg.a + x->u * (seg.b - seg.a);
          if ((p - g.center).norm() < 1e-9) crossed = true;
        }
      }
      CHECK(crossed);
    }
  }

  SECTION("round obstacles: two posts per gate, then the circle obstacles") {
    const auto& round = track.round_obstacles();
    REQUIRE(round.size() == 2 * config.gates.size() + config.obstacles.size());
    for (size_t k = 0; k < track.gates().size(); ++k) {
      const haptel::Gate& g = track.gates()[k];
      int posts_found = 0;
      for (const auto& o : round) {
        if (((o.center - g.left_post).norm() < kTol || (o.center - g.right_post).norm() < kTol) &&
            o.radius == config.post_radius) {
          ++posts_found;
        }
      }
      CHECK(posts_found == 2);
    }
    for (const auto& ob : config.obstacles) {
      bool found = false;
      for (const auto& o : round) {
        if ((o.center - ob.center).norm() < kTol && o.radius == ob.radius) found = true;
      }
      CHECK(found);
    }
  }

  SECTION("start line crosses the corridor at distance 0") {
    const Segment2& start = track.start_line();
    CHECK(DistanceToSegment(start, c[0]) < kTol);
    CHECK(std::abs((start.b - start.a).dot(c[1] - c[0])) < kTol);
    CHECK((start.b - start.a).norm() >= config.corridor_width);
  }

  SECTION("vehicles start start_behind before the start line, facing along the track") {
    const Vec2 p = track.StartPosition();
    // On the centre line ...
    CHECK(std::abs(track.ClosestArcLength(p) - (length - config.start_behind)) < 1e-9);
    // ... start_behind metres of centre line before the start (so no farther in a straight line).
    CHECK((c[0] - p).norm() <= config.start_behind + 1e-9);
    CHECK((c[0] - p).norm() > 0.0);
    const double heading = track.StartHeading();
    const Vec2 facing(std::cos(heading), std::sin(heading));
    // Facing the start line, and along the way the centre line goes on from there.
    CHECK(facing.dot((c[0] - p).normalized()) > 0.5);
    const double s = track.ClosestArcLength(p);
    const Vec2 ahead = (track.PointAt(s + 1e-3) - track.PointAt(s)).normalized();
    CHECK(facing.dot(ahead) > 0.9999);
    CHECK(heading > -std::numbers::pi);
    CHECK(heading <= std::numbers::pi);
  }
}

TEST_CASE("Track: a start behind the start line wraps onto the last segment", "[track]") {
  // A 4 m x 3 m rectangle; starting 1 m back puts the vehicle on the closing
  // segment (0,3)->(0,0), heading down (-y).
  haptel::TrackConfig config;
  config.name = "rect";
  config.centerline = {Vec2(0, 0), Vec2(4, 0), Vec2(4, 3), Vec2(0, 3)};
  config.corridor_width = 1.0;
  config.start_behind = 1.0;
  config.gates = {{2.0, 0.6}};
  const Track track(config);
  CHECK(track.length() == Approx(14.0));
  CHECK((track.StartPosition() - Vec2(0.0, 1.0)).norm() < kTol);
  CHECK(track.StartHeading() == Approx(-std::numbers::pi / 2));
  // Mitred corners: the walls meet at the corner's offset points.
  const Vec2 corner_out(4.5, -0.5);
  const Vec2 corner_in(3.5, 0.5);
  int at_out = 0;
  int at_in = 0;
  for (const auto& w : track.walls()) {
    at_out += ((w.a - corner_out).norm() < kTol) + ((w.b - corner_out).norm() < kTol);
    at_in += ((w.a - corner_in).norm() < kTol) + ((w.b - corner_in).norm() < kTol);
  }
  CHECK(at_out == 2);
  CHECK(at_in == 2);
}

TEST_CASE("a gate's free width: the opening less the obstacles across it (issue 41)") {
  haptel::TrackConfig t;
  t.name = "gate";
  t.centerline = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
  t.corridor_width = 1.0;
  t.post_radius = 0.03;
  t.gates = {{1.0, 0.34}};
  {
    const haptel::Track track(t);
    CHECK(haptel::GateFreeWidth(track, 0) == Approx(0.28));
  }
  // A 0.12-m post in the middle: two gaps of 0.08 m.
  t.obstacles = {{{1.0, 0.0}, 0.06}, {{2.0, 0.0}, 0.06}};
  {
    const haptel::Track track(t);
    std::vector<size_t> blocking;
    CHECK(haptel::GateFreeWidth(track, 0, &blocking) == Approx(0.08));
    CHECK(blocking == std::vector<size_t>{0});
  }
  // Off the line by 0.05 m, a 0.06-m circle takes a chord of 2*sqrt(0.06^2 - 0.05^2) beside a post.
  t.obstacles = {{{1.05, 0.12}, 0.06}};
  {
    const haptel::Track track(t);
    const double chord_half = std::sqrt(0.06 * 0.06 - 0.05 * 0.05);
    // 0.05 m from the left post's centre along the line: the gap left runs
    // from the chord's far end to the right post's surface (0.31 m along).
    CHECK(haptel::GateFreeWidth(track, 0) == Approx(0.31 - (0.05 + chord_half)).margin(1e-9));
  }
  // Touching nothing of the opening: the whole opening.
  t.obstacles = {{{1.0, 0.5}, 0.1}};
  CHECK(haptel::GateFreeWidth(haptel::Track(t), 0) == Approx(0.28));
}
