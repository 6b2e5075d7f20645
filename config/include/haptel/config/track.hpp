#pragma once
/// @file A grand-prix track: a closed corridor with walls, gates and obstacles.
///
/// The file gives a closed centre line; walls are the centre line offset by
/// half the corridor width on each side. Gates are pairs of posts across the
/// centre line at given distances along it; the start/finish line crosses the
/// corridor at distance 0. Vehicles start `start_behind` metres before it.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "haptel/core/geometry2d.hpp"

namespace haptel {

struct GateSpec {
  double along = 0.0;  ///< distance along the centre line from the start line, m
  double width = 0.0;  ///< distance between the two posts' centres, m
};

struct CircleObstacle {
  Vec2 center{0.0, 0.0};
  double radius = 0.1;  ///< m
};

struct TrackConfig {
  std::string name;
  std::filesystem::path file;
  std::vector<Vec2> centerline;  ///< closed loop (last point joins the first), m
  double corridor_width = 1.0;   ///< m
  double post_radius = 0.04;     ///< m
  double start_behind = 0.3;     ///< m before the start line where vehicles start
  double lap_cap_s = 600.0;
  /// The track's baseline, when known: the lap an expert drives at best (the
  /// thesis's grand prix: 1 min 30 s, driven by keyboard in direct view). The
  /// study report gives each lap's percentage over it. Not a trial's
  /// setting: it changes no trial and no score. Between 1 s and lap_cap_s.
  std::optional<double> reference_lap_s;
  std::vector<GateSpec> gates;
  std::vector<CircleObstacle> obstacles;

  /// Throws ConfigFieldError ("gates[1].along", "centerline[3]") unless the
  /// values are in range, the centre line (3 to 2000 points) turns by at most
  /// 135 degrees at a point and never meets itself, the corridor does not
  /// overlap itself, and at least one gate, in increasing order along the
  /// lap, has its posts inside the corridor and its line across it. A
  /// default-constructed TrackConfig has no centre line: it is not valid.
  void ValidateOrThrow() const;
};

/// Loads and validates (TrackConfig::ValidateOrThrow) a track file. Throws
/// ConfigError naming file, key, line.
TrackConfig LoadTrack(const std::filesystem::path& file);

/// A gate as placed on the track.
struct Gate {
  Vec2 center;
  Vec2 tangent;    ///< unit direction of travel
  Vec2 left_post;  ///< centre of the post on the driver's left
  Vec2 right_post;
  Segment2 line;  ///< across the whole corridor, right wall to left wall
  double along = 0.0;
};

/// Geometry derived from a TrackConfig, computed once.
class Track {
 public:
  explicit Track(TrackConfig config);

  const TrackConfig& config() const { return config_; }
  double length() const { return length_; }
  const std::vector<Segment2>& walls() const { return walls_; }
  const std::vector<Gate>& gates() const { return gates_; }
  /// All round posts (gate posts), plus the circle obstacles.
  const std::vector<CircleObstacle>& round_obstacles() const { return round_; }
  const Segment2& start_line() const { return start_line_; }

  /// Point and unit tangent on the centre line at arc length s (wraps).
  Vec2 PointAt(double s) const;
  Vec2 TangentAt(double s) const;
  /// Arc length of the centre-line point closest to p.
  double ClosestArcLength(const Vec2& p) const;
  /// Where vehicles start, and their heading (rad).
  Vec2 StartPosition() const;
  double StartHeading() const;

 private:
  Segment2 CrossLine(double s, double half_width) const;

  TrackConfig config_;
  std::vector<double> cumulative_;  ///< arc length at each centre-line vertex
  double length_ = 0.0;
  std::vector<Segment2> walls_;
  std::vector<Gate> gates_;
  std::vector<CircleObstacle> round_;
  Segment2 start_line_;
};

/// The widest free stretch of gate `index`'s opening, m: along the line
/// between its posts, from one post's surface to the other's, less what the
/// track's obstacles lying across that line take of it (a post in the gate
/// leaves two gaps, the wider one counts). `blocking` receives the indices,
/// in config().obstacles, of the obstacles across it.
double GateFreeWidth(const Track& track, size_t index, std::vector<size_t>* blocking = nullptr);

}  // namespace haptel
