#include "haptel/config/track.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

/// More points than any drawn track needs; the geometry checks below compare
/// every segment with every other.
constexpr size_t kMaxCenterlinePoints = 2000;

std::string NumberText(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

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
void CheckCenterlineSimple(const TrackConfig& t) {
  const auto& c = t.centerline;
  const size_t n = c.size();
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      if (Adjacent(i, j, n)) continue;
      if (const auto p = Meet({c[i], c[(i + 1) % n]}, {c[j], c[(j + 1) % n]})) {
        throw ConfigFieldError(
            "centerline[" + std::to_string(j) + "]", "a closed line that does not cross itself", {},
            "the segment from point " + std::to_string(j) + " crossing the one from point " +
                std::to_string(i) + " at " + PointText(*p));
      }
    }
  }
}

/// The corridor must not overlap itself: no wall crosses another, and no wall
/// corner comes closer to the centre line than half the corridor (a corridor
/// folded over itself in a tight turn, or two parts of the track too close).
void CheckCorridorSimple(const TrackConfig& t, const Track& track) {
  const auto& c = t.centerline;
  const size_t n = c.size();
  const auto& walls = track.walls();  // [2i]: left of segment i, [2i + 1]: right of it
  const char* side[2] = {"left", "right"};
  const std::string fix = " (narrow the corridor or move the centre line's parts apart)";
  for (size_t a = 0; a < walls.size(); ++a) {
    for (size_t b = a + 1; b < walls.size(); ++b) {
      const size_t i = a / 2;
      const size_t j = b / 2;
      if (a % 2 == b % 2 && Adjacent(i, j, n)) continue;  // joined end to end
      if (const auto p = Meet(walls[a], walls[b])) {
        throw ConfigFieldError(
            "corridor_width", "walls that do not cross" + fix, {},
            "the " + std::string(side[a % 2]) + " wall beside the segment from point " +
                std::to_string(i) + " crossing the " + side[b % 2] +
                " wall beside the one from point " + std::to_string(j) + " at " + PointText(*p));
      }
    }
  }
  const double h = t.corridor_width / 2;
  for (size_t w = 0; w < walls.size(); ++w) {
    const Vec2& corner = walls[w].a;  // the wall's corner at point w / 2
    for (size_t j = 0; j < n; ++j) {
      const Vec2 q = ClosestPointOnSegment({c[j], c[(j + 1) % n]}, corner);
      if ((q - corner).norm() < h * (1 - 1e-6)) {
        throw ConfigFieldError(
            "corridor_width", "a corridor that does not overlap itself" + fix, {},
            "the " + std::string(side[w % 2]) + " wall's corner at point " + std::to_string(w / 2) +
                " " + PointText(corner) + " inside the corridor along the segment from point " +
                std::to_string(j));
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

void TrackConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  const size_t n = centerline.size();
  if (n < 3 || n > kMaxCenterlinePoints) {
    check::Fail("centerline", "a list of 3 to " + std::to_string(kMaxCenterlinePoints) +
                                  " points [x, y] in metres");
  }
  for (size_t i = 0; i < n; ++i) {
    if (!centerline[i].allFinite()) {
      check::Fail("centerline[" + std::to_string(i) + "]", "a point [x, y] in metres");
    }
  }
  check::Number("corridor_width", corridor_width, 0.2, 20.0);
  check::Number("post_radius", post_radius, 0.005, 1.0);
  check::Number("start_behind", start_behind, 0.0, 10.0);
  check::Number("lap_cap_s", lap_cap_s, 1.0, 24 * 3600.0);
  if (reference_lap_s && !(*reference_lap_s >= 1.0 && *reference_lap_s <= lap_cap_s)) {
    // A baseline slower than the cap would make every capped lap look fast.
    check::Fail("reference_lap_s", "a lap time in s from 1 to the lap cap (lap_cap_s = " +
                                       NumberText(lap_cap_s) + ")");
  }
  for (size_t i = 0; i < gates.size(); ++i) {
    const std::string key = "gates[" + std::to_string(i) + "]";
    check::Number(key + ".along", gates[i].along, 0.0, 1e6);
    check::Number(key + ".width", gates[i].width, 0.05, 20.0);
  }
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const std::string key = "obstacles[" + std::to_string(i) + "]";
    if (!obstacles[i].center.allFinite()) check::Fail(key + ".center", "a point [x, y] in metres");
    check::Number(key + ".radius", obstacles[i].radius, 0.005, 10.0);
  }

  // Rules between several values.
  double length = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Vec2 d0 = centerline[i] - centerline[(i + n - 1) % n];
    const Vec2 d1 = centerline[(i + 1) % n] - centerline[i];
    if (d1.norm() < 1e-6) {
      check::Fail("centerline[" + std::to_string((i + 1) % n) + "]",
                  "a point distinct from the one before it");
    }
    const double turn = std::abs(WrapAngle(std::atan2(Cross2(d0, d1), d0.dot(d1))));
    if (turn > 0.75 * std::numbers::pi) {
      check::Fail("centerline[" + std::to_string(i) + "]",
                  "a point where the centre line turns by at most 135 degrees");
    }
    length += d1.norm();
  }
  if (gates.empty()) check::Fail("gates", "a list of at least one gate");
  double previous = 0.0;
  for (size_t i = 0; i < gates.size(); ++i) {
    const GateSpec& g = gates[i];
    const std::string key = "gates[" + std::to_string(i) + "]";
    if (g.along <= previous || g.along >= length) {
      check::Fail(key + ".along",
                  "gates in increasing order strictly between 0 and the track length " +
                      std::to_string(length) + " m");
    }
    if (g.width / 2 + post_radius >= corridor_width / 2) {
      check::Fail(key + ".width",
                  "posts inside the corridor (width + 2*post_radius < corridor_width)");
    }
    previous = g.along;
  }

  // The corridor's shape: one lane that never meets itself, and lines that cross it.
  CheckCenterlineSimple(*this);
  const Track track(*this);
  CheckCorridorSimple(*this, track);
  for (size_t i = 0; i < gates.size(); ++i) {
    const std::string problem = CrossLineProblem(track.gates()[i].line, track);
    if (!problem.empty()) {
      throw ConfigFieldError(
          "gates[" + std::to_string(i) + "].along",
          "a gate whose line crosses the corridor from wall to wall", {},
          "a line at " + PointText(track.gates()[i].center) + " that " + problem);
    }
  }
}

TrackConfig LoadTrack(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  TrackConfig t;
  t.file = file;
  t.name = root.RequireString("name");
  t.centerline = root.Points("centerline", 0);
  t.corridor_width = root.RequireNumber("corridor_width");
  t.post_radius = root.Number("post_radius", t.post_radius);
  t.start_behind = root.Number("start_behind", t.start_behind);
  t.lap_cap_s = root.Number("lap_cap_s", t.lap_cap_s);
  if (root.Has("reference_lap_s")) t.reference_lap_s = root.RequireNumber("reference_lap_s");
  // The width of every gate that gives none.
  const double default_gate_width = root.Number("gate_width", 0.6 * t.corridor_width);
  for (YamlMap& g : root.MapList("gates")) {
    GateSpec spec;
    spec.along = g.RequireNumber("along");
    spec.width = g.Number("width", default_gate_width);
    g.Finish();
    t.gates.push_back(spec);
  }
  for (YamlMap& o : root.MapList("obstacles")) {
    CircleObstacle c;
    c.center = o.Point("center");
    c.radius = o.RequireNumber("radius");
    o.Finish();
    t.obstacles.push_back(c);
  }
  root.Finish();
  try {
    t.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    // A gate without a width of its own has gate_width's: say so at the gate.
    const bool gate_width = e.key.rfind("gates[", 0) == 0 && e.key.size() > 6 &&
                            e.key.compare(e.key.size() - 6, 6, ".width") == 0;
    root.Fail(e, gate_width ? "got " + NumberText(default_gate_width) + " (from gate_width)"
                            : "but it is missing");
  }
  return t;
}

Track::Track(TrackConfig config) : config_(std::move(config)) {
  const auto& c = config_.centerline;
  const size_t n = c.size();
  cumulative_.resize(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i)
    cumulative_[i + 1] = cumulative_[i] + (c[(i + 1) % n] - c[i]).norm();
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

double GateFreeWidth(const Track& track, size_t index, std::vector<size_t>* blocking) {
  const Gate& gate = track.gates().at(index);
  const double post = track.config().post_radius;
  const Vec2 across = gate.right_post - gate.left_post;
  const double length = across.norm();
  const Vec2 u = across / length;
  // Stretches of the line [0, length] taken: the posts, and each obstacle's chord.
  std::vector<std::pair<double, double>> taken = {{-post, post}, {length - post, length + post}};
  const std::vector<CircleObstacle>& obstacles = track.config().obstacles;
  for (size_t i = 0; i < obstacles.size(); ++i) {
    const Vec2 v = obstacles[i].center - gate.left_post;
    const double t = v.dot(u);
    const double d = (v - t * u).norm();
    const double r = obstacles[i].radius;
    if (d >= r) continue;
    const double half = std::sqrt(r * r - d * d);
    if (t + half <= post || t - half >= length - post) continue;  // beyond the posts
    taken.push_back({t - half, t + half});
    if (blocking != nullptr) blocking->push_back(i);
  }
  std::sort(taken.begin(), taken.end());
  double widest = 0.0;
  double reach = taken.front().second;
  for (const auto& [from, to] : taken) {
    widest = std::max(widest, std::min(from, length - post) - reach);
    reach = std::max(reach, to);
  }
  return widest;
}

}  // namespace haptel
