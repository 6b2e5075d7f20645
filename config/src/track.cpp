#include "haptel/config/track.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

namespace {

/// More points than any drawn track needs; the geometry checks below compare
/// every segment with every other.
constexpr size_t kMaxCenterlinePoints = 2000;

std::string PointText(const Vec2& p) {
  char text[64];
  std::snprintf(text, sizeof text, "(%.3g, %.3g)", p.x(), p.y());
  return text;
}

/// Where segments a and b meet (cross, touch, or overlap along one line), if they do.
std::optional<Vec2> Meet(const Segment2& a, const Segment2& b) {
  if (const auto c = SegmentCrossing(a.a, a.b, b)) return Vec2(a.a + (a.b - a.a) * c->t);
  constexpr double kTouch = 1e-9;  // m; parallel segments meet where an end lies on the other
  for (const Vec2& p : {a.a, a.b}) {
    if ((ClosestPointOnSegment(b, p) - p).norm() < kTouch) return p;
  }
  for (const Vec2& p : {b.a, b.b}) {
    if ((ClosestPointOnSegment(a, p) - p).norm() < kTouch) return p;
  }
  return std::nullopt;
}

/// Segments i and j of a closed line of n segments share a point.
bool Adjacent(size_t i, size_t j, size_t n) { return (i + 1) % n == j || (j + 1) % n == i; }

/// The centre line must not cross itself (a figure 8, a bow tie).
void CheckCenterlineSimple(const TrackConfig& t, const YamlMap& root) {
  const auto& c = t.centerline;
  const size_t n = c.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (Adjacent(i, j, n)) continue;
      if (const auto p = Meet({c[i], c[(i + 1) % n]}, {c[j], c[(j + 1) % n]})) {
        throw ConfigError(root.ItemLocation("centerline", j) +
                          ": key 'centerline': expected a closed line that does not cross "
                          "itself, but the segment from point " +
                          std::to_string(j) + " crosses the one from point " + std::to_string(i) +
                          " at " + PointText(*p));
      }
    }
  }
}

/// The corridor must not overlap itself: no wall crosses another, and no wall
/// corner comes closer to the centre line than half the corridor (a corridor
/// folded over itself in a tight turn, or two parts of the track too close).
void CheckCorridorSimple(const TrackConfig& t, const Track& track, YamlMap& root) {
  const auto& c = t.centerline;
  const size_t n = c.size();
  const auto& walls = track.walls();  // [2i]: left of segment i, [2i + 1]: right of it
  const char* side[2] = {"left", "right"};
  const std::string fix = "; narrow the corridor or move the centre line's parts apart";
  for (size_t a = 0; a < walls.size(); ++a) {
    for (size_t b = a + 1; b < walls.size(); ++b) {
      const size_t i = a / 2;
      const size_t j = b / 2;
      if (a % 2 == b % 2 && Adjacent(i, j, n)) continue;  // joined end to end
      if (const auto p = Meet(walls[a], walls[b])) {
        root.Fail("corridor_width", "walls that do not cross, but the " + std::string(side[a % 2]) +
                                        " wall beside the segment from point " + std::to_string(i) +
                                        " crosses the " + side[b % 2] +
                                        " wall beside the one from point " + std::to_string(j) +
                                        " at " + PointText(*p) + fix);
      }
    }
  }
  const double h = t.corridor_width / 2;
  for (size_t w = 0; w < walls.size(); ++w) {
    const Vec2& corner = walls[w].a;  // the wall's corner at point w / 2
    for (size_t j = 0; j < n; ++j) {
      const Vec2 q = ClosestPointOnSegment({c[j], c[(j + 1) % n]}, corner);
      if ((q - corner).norm() < h * (1 - 1e-6)) {
        root.Fail("corridor_width", "a corridor that does not overlap itself, but the " +
                                        std::string(side[w % 2]) + " wall's corner at point " +
                                        std::to_string(w / 2) + " " + PointText(corner) +
                                        " lies inside the corridor along the segment from point " +
                                        std::to_string(j) + fix);
      }
    }
  }
}

/// Why a line across the corridor does not do its job ("" when it does): it
/// must reach the wall on each side, and no further part of the track.
std::string CrossLineProblem(const Segment2& line, const Track& track) {
  // Crossings with the walls, by position along the line (0: right end, 1: left end).
  struct Hit {
    double t;
    bool left;
  };
  std::vector<Hit> hits;
  const auto& walls = track.walls();
  for (size_t w = 0; w < walls.size(); ++w) {
    if (const auto c = SegmentCrossing(line.a, line.b, walls[w])) {
      hits.push_back({c->t, w % 2 == 0});
    }
  }
  const double length = (line.b - line.a).norm();
  for (const bool left : {true, false}) {
    const char* name = left ? "left" : "right";
    // The side's crossings from the centre outwards; one wall (or two walls
    // meeting at a corner) at one place.
    std::vector<Hit> side;
    for (const Hit& h : hits) {
      if ((h.t > 0.5) == left) side.push_back(h);
    }
    std::sort(side.begin(), side.end(),
              [](const Hit& x, const Hit& y) { return std::abs(x.t - 0.5) < std::abs(y.t - 0.5); });
    if (side.empty() || side.front().left != left) {
      return std::string("does not reach the ") + name +
             " wall (a turn too sharp for the corridor there)";
    }
    for (const Hit& h : side) {
      if (std::abs(h.t - side.front().t) * length > 1e-9) {
        return std::string("reaches past the ") + name + " wall into another part of the track";
      }
    }
  }
  return {};
}

}  // namespace

TrackConfig LoadTrack(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  TrackConfig t;
  t.file = file;
  t.name = root.RequireString("name");
  t.centerline = root.Points("centerline", 3);
  if (t.centerline.size() > kMaxCenterlinePoints) {
    root.Fail("centerline", "at most " + std::to_string(kMaxCenterlinePoints) + " points");
  }
  t.corridor_width = root.RequireNumber("corridor_width", 0.2, 20.0);
  t.post_radius = root.Number("post_radius", t.post_radius, 0.005, 1.0);
  t.start_behind = root.Number("start_behind", t.start_behind, 0.0, 10.0);
  t.lap_cap_s = root.Number("lap_cap_s", t.lap_cap_s, 1.0, 24 * 3600.0);
  const double default_gate_width = root.Number("gate_width", 0.6 * t.corridor_width, 0.05, 20.0);
  // Kept for the checks below, so their errors point at the gate's line.
  std::vector<YamlMap> gate_maps = root.MapList("gates");
  for (YamlMap& g : gate_maps) {
    GateSpec spec;
    spec.along = g.RequireNumber("along", 0.0, 1e6);
    spec.width = g.Number("width", default_gate_width, 0.05, 20.0);
    g.Finish();
    t.gates.push_back(spec);
  }
  for (YamlMap& o : root.MapList("obstacles")) {
    CircleObstacle c;
    c.center = o.Point("center");
    c.radius = o.RequireNumber("radius", 0.005, 10.0);
    o.Finish();
    t.obstacles.push_back(c);
  }
  root.Finish();

  // Checks that need several keys at once.
  const size_t n = t.centerline.size();
  double length = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Vec2 d0 = t.centerline[i] - t.centerline[(i + n - 1) % n];
    const Vec2 d1 = t.centerline[(i + 1) % n] - t.centerline[i];
    if (d1.norm() < 1e-6) root.Fail("centerline", "distinct consecutive points");
    const double turn = std::abs(WrapAngle(std::atan2(Cross2(d0, d1), d0.dot(d1))));
    if (turn > 0.75 * std::numbers::pi) {
      root.Fail("centerline", "no turn sharper than 135 degrees (point " + std::to_string(i) + ")");
    }
    length += d1.norm();
  }
  if (t.gates.empty()) root.Fail("gates", "a list of at least one gate");
  double previous = 0.0;
  for (size_t i = 0; i < t.gates.size(); ++i) {
    const GateSpec& g = t.gates[i];
    YamlMap& map = gate_maps[i];
    if (g.along <= previous || g.along >= length) {
      map.Fail("along", "gates in increasing order strictly between 0 and the track length " +
                            std::to_string(length) + " m");
    }
    if (g.width / 2 + t.post_radius >= t.corridor_width / 2) {
      const std::string expected =
          "posts inside the corridor (width + 2*post_radius < corridor_width)";
      if (map.Has("width")) map.Fail("width", expected);
      // The width came from gate_width: name this gate, at its line.
      throw ConfigError(map.Location() + ": key '" + map.Path("width") + "': expected " +
                        expected + ", got " + std::to_string(g.width) + " (from gate_width)");
    }
    previous = g.along;
  }

  // The corridor's shape: one lane that never meets itself, and lines that cross it.
  CheckCenterlineSimple(t, root);
  const Track track(t);
  CheckCorridorSimple(t, track, root);
  for (size_t i = 0; i < t.gates.size(); ++i) {
    const std::string problem = CrossLineProblem(track.gates()[i].line, track);
    if (!problem.empty()) {
      gate_maps[i].Fail("along",
                        "a gate whose line crosses the corridor from wall to wall, but at " +
                            PointText(track.gates()[i].center) + " it " + problem);
    }
  }
  return t;
}

Track::Track(TrackConfig config) : config_(std::move(config)) {
  const auto& c = config_.centerline;
  const size_t n = c.size();
  cumulative_.resize(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) cumulative_[i + 1] = cumulative_[i] + (c[(i + 1) % n] - c[i]).norm();
  length_ = cumulative_[n];

  // Walls: the centre line offset by half the corridor width, mitred joins.
  const double h = config_.corridor_width / 2;
  std::vector<Vec2> left(n);
  std::vector<Vec2> right(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec2 d0 = (c[i] - c[(i + n - 1) % n]).normalized();
    const Vec2 d1 = (c[(i + 1) % n] - c[i]).normalized();
    const Vec2 n0(-d0.y(), d0.x());
    const Vec2 n1(-d1.y(), d1.x());
    const Vec2 miter = (n0 + n1).normalized();
    const double len = h / miter.dot(n0);
    left[i] = c[i] + miter * len;
    right[i] = c[i] - miter * len;
  }
  for (size_t i = 0; i < n; ++i) {
    walls_.push_back({left[i], left[(i + 1) % n]});
    walls_.push_back({right[i], right[(i + 1) % n]});
  }

  for (const GateSpec& spec : config_.gates) {
    Gate g;
    g.along = spec.along;
    g.center = PointAt(spec.along);
    g.tangent = TangentAt(spec.along);
    const Vec2 normal(-g.tangent.y(), g.tangent.x());
    g.left_post = g.center + normal * (spec.width / 2);
    g.right_post = g.center - normal * (spec.width / 2);
    g.line = CrossLine(spec.along, h);
    gates_.push_back(g);
    round_.push_back({g.left_post, config_.post_radius});
    round_.push_back({g.right_post, config_.post_radius});
  }
  for (const auto& o : config_.obstacles) round_.push_back(o);
  start_line_ = CrossLine(0.0, h);
}

Segment2 Track::CrossLine(double s, double half_width) const {
  const Vec2 p = PointAt(s);
  const Vec2 t = TangentAt(s);
  const Vec2 normal(-t.y(), t.x());
  // A little past the walls so a vehicle scraping a wall still crosses it.
  const double reach = half_width * 1.2;
  return {p - normal * reach, p + normal * reach};
}

namespace {
size_t SegmentIndex(const std::vector<double>& cumulative, double s) {
  size_t i = 0;
  while (i + 2 < cumulative.size() && cumulative[i + 1] <= s) ++i;
  return i;
}
}  // namespace

Vec2 Track::PointAt(double s) const {
  s = std::fmod(s, length_);
  if (s < 0) s += length_;
  const auto& c = config_.centerline;
  const size_t i = SegmentIndex(cumulative_, s);
  const Vec2 a = c[i];
  const Vec2 b = c[(i + 1) % c.size()];
  const double seg = cumulative_[i + 1] - cumulative_[i];
  return a + (b - a) * ((s - cumulative_[i]) / seg);
}

Vec2 Track::TangentAt(double s) const {
  s = std::fmod(s, length_);
  if (s < 0) s += length_;
  const auto& c = config_.centerline;
  const size_t i = SegmentIndex(cumulative_, s);
  return (c[(i + 1) % c.size()] - c[i]).normalized();
}

double Track::ClosestArcLength(const Vec2& p) const {
  const auto& c = config_.centerline;
  double best = std::numeric_limits<double>::infinity();
  double best_s = 0.0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Segment2 seg{c[i], c[(i + 1) % c.size()]};
    const Vec2 q = ClosestPointOnSegment(seg, p);
    const double d = (q - p).squaredNorm();
    if (d < best) {
      best = d;
      best_s = cumulative_[i] + (q - seg.a).norm();
    }
  }
  return best_s;
}

Vec2 Track::StartPosition() const { return PointAt(-config_.start_behind); }

double Track::StartHeading() const {
  const Vec2 t = TangentAt(-config_.start_behind);
  return std::atan2(t.y(), t.x());
}

}  // namespace haptel
