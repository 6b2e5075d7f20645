#include "haptel/config/track.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

TrackConfig LoadTrack(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  TrackConfig t;
  t.file = file;
  t.name = root.RequireString("name");
  t.centerline = root.Points("centerline", 3);
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
