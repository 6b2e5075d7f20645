#pragma once
/// @file Where the robot is on the track it drives, from its odometry and its
/// range scan against the track's known walls and posts: the operator side's
/// correction of the odometry's drift (a skid the encoders cannot see, a
/// gyro's bias, a floor patch), never from the vehicle's truth.
///
/// An extended Kalman filter on the pose (x, y, heading), as in Thrun,
/// Burgard and Fox, *Probabilistic Robotics* (2005), ch. 7.4 (EKF
/// localisation), with:
/// - the odometry motion model (ch. 5.4): each state's odometry pose, taken
///   as an increment in the robot's frame since the previous state's, moves
///   the estimate; its noise grows with the distance and the turn (and with
///   the distance alone while a bumper is pressed: treads slipping on a
///   wall move the encoders, not the robot);
/// - the likelihood-field measurement model (ch. 6.4): a beam that meets
///   something ends on the track's walls or posts, so its endpoint's distance
///   to the nearest of them is a measurement of zero. Beams that read max
///   range tell nothing (the book's z_max: a missing echo is no evidence);
///   an endpoint farther than a gate from everything is an outlier. The
///   update is iterated (Gauss-Newton on the prior and every beam,
///   re-associating each beam with its nearest shape every iteration: the
///   iterated EKF of Bell and Cathey, 1993), each beam gated at 3 sd of what
///   the prior allows it and weighted by Huber's function beyond 2 sd: a
///   false echo or a misplaced post pulls with a bounded force, or none.
///   (The book's z_hit/z_rand mixture weight, tried in its place, held the
///   pose less well on false echoes: docs/architecture.md.)
/// - an innovation gate on the whole scan: when fewer than
///   min_inlier_fraction of the beams that met something end within 3 sd
///   of the map at the pose the update found, the scan disagrees with the
///   map wherever the robot is (a sensor's bad frame, a lidar whose angle
///   slipped, a crowd around the robot): it is refused, and the pose
///   stays the odometry's (scans_refused counts them);
/// - the map's own error: a correction the map's error can explain (a few
///   centimetres) is taken at a small fraction of the scan's information,
///   so that the pose follows the odometry and averages the walls' and
///   posts' errors over the track instead of snapping to the nearest ones
///   (lab's grand prix, seeds 1-20 in simulated time: the localised pose's
///   p95 against the truth in the map's frame from 29.6 to 22.4 mm, mean;
///   harsh's, whose odometry drifts faster, from 66 to 87 mm: see
///   docs/benchmarks.md); a larger one, the odometry's drift, is taken
///   whole (LocaliserConfig::map_error_m).
///
/// With LocaliserConfig::learn_map it learns the map as it drives: EKF-SLAM
/// with known shapes (Probabilistic Robotics, ch. 10.2, the landmarks here
/// the track's own shapes, their association the nearest-shape field's).
/// The state is the pose and a 2-D offset from the file for each unique
/// wall corner (a corner two walls share is one offset: they keep meeting
/// there) and each post's centre, each offset's prior mean 0 and sd
/// corner_sd_m / post_sd_m, with the full joint covariance. A beam's
/// distance to a displaced shape depends on its offsets: a wall's on its
/// corners a and b by −(1−t)·n and −t·n (t where the endpoint's foot falls
/// on it, n the unit normal toward the endpoint), a post's on its centre by
/// −n; the same iterated update, gates and Huber weights take them in, in
/// covariance form restricted to the shapes the scan saw (the Woodbury
/// identity: a k×k solve, k ≤ 3 + 2·kMaxSeenShapes, then an n·k·n
/// covariance update). Offsets are clamped to offset_bound_m, and the
/// nearest-shape grid is widened by it, so it still holds every shape that
/// can be nearest once displaced. A post that stands 5 cm from the file is
/// then learnt where it stands and the pose is no longer pulled 5 cm by it;
/// without learn_map, nothing of this runs and the localiser is as before.
/// The map-error band below is not applied when learning: the map's error
/// is in the state, and the band, which takes a few centimetres' correction
/// at 0.3 % weight, would learn the map at that rate too (harsh, 400 ms, 10
/// seeds: the localised pose's p95 44 mm without it, 73 mm with it). The
/// price of learning is on an exact map: the pose floats within what the
/// map learnt is sure of (the `none` twin: 1.7 mm p95 against 0.3 mm on
/// the file's map; see docs/benchmarks.md).
///
/// The nearest shapes are looked up in a grid precomputed from the track
/// (each cell lists the shapes that can be nearest to a point in it), and the
/// distance to them is exact, so the field has no grid error. All memory is
/// taken at construction: an update allocates nothing. Deterministic: no
/// random draw.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/core/range_scan.hpp"

namespace haptel::mediator {

/// A planar pose (m, m, rad).
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
};

/// The filter's noise model. Defaults fit a small tracked robot with a
/// low-cost scanning range sensor on a hand-laid track (config/realities/
/// lab.yaml's spreads, with margin): the model's, not the reality's (which
/// the operator side never reads).
struct LocaliserConfig {
  /// A beam's endpoint against the map (m): the sensor's noise and the
  /// map's error, inflated because beams of one scan are not independent
  /// (ch. 6.3.4; the beams on one misplaced wall share its error).
  double beam_sd = 0.02;
  /// The map's own error (m): a lab's walls and posts stand a few
  /// centimetres from the file, and every beam of a scan, and every scan
  /// while the same walls are in view, shares that error (ch. 6.3.4: the
  /// measurements are not independent). A correction smaller than this
  /// (its size: the distance plus heading_lever_m times the turn) is what
  /// the map's error can explain: the scan weighs within_map_error_weight
  /// of its information, so the pose follows the odometry and averages the
  /// map's errors over the walls and posts it passes. A larger one is the
  /// odometry's drift: its weight rises to the whole scan's at twice this.
  /// 0: every scan taken whole. Not applied with learn_map (see above).
  double map_error_m = 0.04;
  double within_map_error_weight = 0.003;
  double heading_lever_m = 0.5;
  /// A scan is refused when fewer than this fraction of its beams that met
  /// something end within 3 beam_sd of the map at the pose found.
  double min_inlier_fraction = 0.5;
  /// Beyond this from every wall and post (m), an endpoint is an outlier.
  double outlier_m = 0.3;
  /// Odometry noise per metre driven: along, across (m/m), and heading
  /// (rad/m); and per radian turned (rad/rad).
  double along_per_m = 0.1;
  double across_per_m = 0.05;
  double heading_per_m = 0.05;
  double heading_per_rad = 0.05;
  /// Along the heading per metre the treads drive while a bumper is pressed.
  double pressed_along_per_m = 1.0;
  /// Added each update, however still the robot (m, rad): what the
  /// odometry cannot see at all.
  double floor_m = 0.001;
  double floor_rad = 0.001;
  /// The first pose's uncertainty (m, rad): odometry starts where the
  /// vehicle was placed.
  double initial_sd_m = 0.05;
  double initial_sd_rad = 0.05;
  /// Gauss-Newton iterations per scan at most.
  int iterations = 10;
  /// Learn the map as it drives (see above): the wall corners' and posts'
  /// offsets from the file, their prior sd (m; a track laid by hand with a
  /// tape measure from a drawing: each corner and post a few centimetres
  /// from where the drawing says, the same belief for both: the model's,
  /// not a reality's), and the largest offset learnt (m; 4 sd: the grid's
  /// margin, so a larger bound costs lookups).
  bool learn_map = false;
  double corner_sd_m = 0.03;
  double post_sd_m = 0.03;
  double offset_bound_m = 0.12;
  /// OnFileMap's reach (m): about a corridor's width, the walls and posts
  /// that bound it where the robot is.
  double local_radius_m = 1.0;
};

/// A wall corner or a post's centre: where the file has it, and where the
/// localiser has learnt it stands (the file's, without learn_map).
struct MapFeature {
  Vec2 file = Vec2::Zero();
  Vec2 learnt = Vec2::Zero();
};

class TrackLocaliser {
 public:
  /// Precomputes the track's nearest-shape grid (the walls and round posts,
  /// Track::walls and Track::round_obstacles).
  explicit TrackLocaliser(const Track& track, const LocaliserConfig& config = {});

  /// Starts at `pose` with these standard deviations; the next Update's
  /// odometry is the origin of the increments.
  void Reset(const Pose2& pose, double sd_m, double sd_rad);
  /// One state: `odometry` the pose the robot reports, `scan` its ranges
  /// from the same moment, `pressed` a bumper closed. The first update (or
  /// the first after Reset without one) starts at the odometry pose unless
  /// Reset gave one. Returns the pose corrected.
  const Pose2& Update(const Pose2& odometry, const RangeScan& scan, bool pressed);

  const Pose2& pose() const { return pose_; }
  /// The pose's covariance, row-major (x, y, heading).
  const std::array<double, 9>& covariance() const { return cov_; }
  /// Beams the last update used (hit something, not outliers; 0 when it
  /// was refused).
  int beams_used() const { return beams_used_; }
  /// Scans refused by the innovation gate since construction.
  int64_t scans_refused() const { return scans_refused_; }
  bool started() const { return started_; }
  /// The map as learnt: each unique wall corner (in the order of the walls,
  /// a before b) and then each post's centre (Track::round_obstacles).
  std::vector<MapFeature> Map() const;
  /// `pose` (in the map as learnt) carried to the same place among the
  /// file's walls and posts: the rigid motion that best takes the learnt
  /// features near it onto the file's (weighted least squares, weights
  /// exp(-d²/2r²) with d the feature's distance from the pose and r
  /// config local_radius_m), applied to it. What a driver steering by the
  /// corridor around the robot sees of it on the file's track, however the
  /// learnt map's frame has settled. `pose` itself without learn_map.
  /// Allocation-free.
  Pose2 OnFileMap(const Pose2& pose) const;
  /// The joint state's size: 3, and 2 per feature with learn_map.
  int state_size() const { return 3 + static_cast<int>(offsets_.size()); }

  /// Distance (m) from `p` to the nearest wall or post surface, and its
  /// gradient (unit, away from that surface); false when nothing is within
  /// the outlier distance (the field's lookup, exposed for tests).
  bool Field(double px, double py, double& distance, double& gx, double& gy) const;

 private:
  struct Circle {
    double cx, cy, r;
  };
  struct Wall {
    double ax, ay, bx, by;
  };
  /// Distance to shape `index` (walls first, then circles) and its gradient;
  /// `t`, if given, where the foot falls along a wall (0 at a, 1 at b).
  double ShapeDistance(uint32_t index, double px, double py, double& gx, double& gy,
                       double* t = nullptr) const;
  /// Field's lookup, saying which shape is nearest and where on it.
  bool Nearest(double px, double py, double& distance, double& gx, double& gy, uint32_t& shape,
               double& t) const;
  void Motion(const Pose2& odometry, bool pressed);
  /// The innovation gate: whether at least min_inlier_fraction of the beams
  /// that met something end within 3 beam_sd of the map at this pose.
  bool Agrees(const RangeScan& scan, double x, double y, double heading) const;
  void Correct(const RangeScan& scan);
  /// learn_map's update (Correct's, with the map's offsets in the state):
  /// each iteration linearises the scan on the parameters it saw
  /// (LineariseWithMap: returns the beams used) and steps from the prior
  /// (StepFromPrior), into the pose and offsets_.
  void CorrectWithMap(const RangeScan& scan);
  struct SeenSystem;
  int LineariseWithMap(const RangeScan& scan, const Eigen::Vector3d& prior,
                       const Eigen::Vector3d& x, SeenSystem& system);
  void StepFromPrior(const Eigen::Vector3d& prior, SeenSystem& system, Eigen::Vector3d& pose);
  /// Moves walls_ and circles_ to the file's shapes displaced by `offsets`.
  void PlaceShapes(const Eigen::VectorXd& offsets);

  LocaliserConfig config_;
  std::vector<Wall> walls_;
  std::vector<Circle> circles_;
  // The grid: cell (i, j) covers [x0 + i·cell, +cell) × [y0 + j·cell, +cell);
  // its candidate shapes are candidates_[starts_[c] .. starts_[c + 1]).
  double x0_ = 0.0, y0_ = 0.0, cell_ = 0.05;
  int nx_ = 0, ny_ = 0;
  std::vector<uint32_t> starts_;
  std::vector<uint32_t> candidates_;

  // learn_map: the file's shapes (walls_ and circles_ are them displaced by
  // the offsets learnt), each wall's corners, and the joint state: the
  // offsets (corners' then posts', x and y each) and the covariance of the
  // pose and offsets, pose first; the rest the update's working memory,
  // sized at construction.
  std::vector<Wall> file_walls_;
  std::vector<Circle> file_circles_;
  std::vector<std::array<uint32_t, 2>> wall_corners_;
  std::vector<Vec2> corners_;
  Eigen::VectorXd offsets_;
  Eigen::MatrixXd joint_cov_;
  Eigen::VectorXd prior_offsets_, step_offsets_;
  Eigen::MatrixXd seen_cov_, seen_gain_;
  std::vector<int> slot_;

  Pose2 pose_;
  std::array<double, 9> cov_{};
  Pose2 last_odometry_;
  bool started_ = false;
  bool have_odometry_ = false;
  int beams_used_ = 0;
  int64_t scans_refused_ = 0;
};

}  // namespace haptel::mediator
