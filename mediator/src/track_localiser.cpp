#include "haptel/mediator/track_localiser.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "haptel/core/geometry2d.hpp"

namespace haptel::mediator {

namespace {

/// The grid's cell (m) and the most cells it may have (a larger track gets
/// coarser cells: more candidates each, the same exact distances).
constexpr double kCell_m = 0.05;
constexpr size_t kMaxCells = 4'000'000;
/// learn_map: the most shapes one scan's update moves (each beam's nearest:
/// a wall's two corners or a post). A beam on a shape beyond them corrects
/// the pose with the shape held where it is learnt.
constexpr int kMaxSeenFeatures = 24;
constexpr int kMaxSeen = 3 + 2 * kMaxSeenFeatures;
using MatSeen = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxSeen, kMaxSeen>;
using VecSeen = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxSeen, 1>;

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;

Mat3 ToMat(const std::array<double, 9>& a) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.data());
}
void FromMat(const Mat3& m, std::array<double, 9>& a) {
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(a.data()) = m;
}
std::array<double, 9> Diagonal(double sd_m, double sd_rad) {
  return {sd_m * sd_m, 0.0, 0.0, 0.0, sd_m * sd_m, 0.0, 0.0, 0.0, sd_rad * sd_rad};
}

/// Each beam of `scan` that met something (a hit, a positive range), seen
/// from the pose (x, y, heading): visit(r, cos, sin, end_x, end_y), the
/// beam's direction and where it ended.
template <class Visit>
void ForEachHit(const RangeScan& scan, double x, double y, double heading, Visit&& visit) {
  for (int i = 0; i < scan.count; ++i) {
    const double r = scan.ranges[static_cast<size_t>(i)];
    if (!scan.Hit(i) || !(r > 0.0)) continue;
    const double angle = heading + scan.Angle(i);
    const double ca = std::cos(angle), sa = std::sin(angle);
    visit(r, ca, sa, x + r * ca, y + r * sa);
  }
}

}  // namespace

TrackLocaliser::TrackLocaliser(const Track& track, const LocaliserConfig& config)
    : config_(config) {
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x;
  double hi_x = -lo_x, hi_y = -lo_x;
  auto extend = [&](double x, double y, double r) {
    lo_x = std::min(lo_x, x - r);
    lo_y = std::min(lo_y, y - r);
    hi_x = std::max(hi_x, x + r);
    hi_y = std::max(hi_y, y + r);
  };
  for (const Segment2& w : track.walls()) {
    walls_.push_back({w.a.x(), w.a.y(), w.b.x(), w.b.y()});
    extend(w.a.x(), w.a.y(), 0.0);
    extend(w.b.x(), w.b.y(), 0.0);
  }
  for (const CircleObstacle& c : track.round_obstacles()) {
    circles_.push_back({c.center.x(), c.center.y(), c.radius});
    extend(c.center.x(), c.center.y(), c.radius);
  }
  const size_t shapes = walls_.size() + circles_.size();
  if (config_.learn_map) {
    // Each unique corner once, in the order of the walls (as a reality
    // draws them and the scoring pairs them), then the posts.
    file_walls_ = walls_;
    file_circles_ = circles_;
    for (const Wall& w : walls_) {
      std::array<uint32_t, 2> ends{};
      for (int e = 0; e < 2; ++e) {
        const Vec2 p = e == 0 ? Vec2(w.ax, w.ay) : Vec2(w.bx, w.by);
        const auto found = std::find(corners_.begin(), corners_.end(), p);
        ends[static_cast<size_t>(e)] = static_cast<uint32_t>(found - corners_.begin());
        if (found == corners_.end()) corners_.push_back(p);
      }
      wall_corners_.push_back(ends);
    }
    const Eigen::Index features = static_cast<Eigen::Index>(corners_.size() + circles_.size());
    offsets_ = Eigen::VectorXd::Zero(2 * features);
    prior_offsets_ = offsets_;
    step_offsets_ = offsets_;
    joint_cov_ = Eigen::MatrixXd::Zero(3 + 2 * features, 3 + 2 * features);
    for (Eigen::Index f = 0; f < features; ++f) {
      const double sd =
          f < static_cast<Eigen::Index>(corners_.size()) ? config_.corner_sd_m : config_.post_sd_m;
      joint_cov_(3 + 2 * f, 3 + 2 * f) = joint_cov_(4 + 2 * f, 4 + 2 * f) = sd * sd;
    }
    seen_cov_ = Eigen::MatrixXd::Zero(3 + 2 * features, kMaxSeen);
    seen_gain_ = seen_cov_;
    slot_.assign(static_cast<size_t>(features), -1);
  }
  if (shapes == 0) return;  // nothing to localise against: every endpoint is an outlier

  // A displaced shape is within `bound` of the file's everywhere (a wall's
  // points are its corners' blends): its distance from a point differs from
  // the file's by at most that, so the margins below widen by it.
  const double bound = config_.learn_map ? config_.offset_bound_m : 0.0;
  // Cells: the shapes' box with the outlier distance around it.
  cell_ = kCell_m;
  const double margin = config_.outlier_m + 2.0 * cell_ + bound;
  for (;;) {
    x0_ = lo_x - margin;
    y0_ = lo_y - margin;
    nx_ = static_cast<int>(std::ceil((hi_x - lo_x + 2.0 * margin) / cell_));
    ny_ = static_cast<int>(std::ceil((hi_y - lo_y + 2.0 * margin) / cell_));
    if (static_cast<size_t>(nx_) * static_cast<size_t>(ny_) <= kMaxCells) break;
    cell_ *= 2.0;
  }
  const size_t cells = static_cast<size_t>(nx_) * static_cast<size_t>(ny_);
  const double diagonal = cell_ * std::sqrt(2.0);
  // A shape is a candidate of a cell when a point of the cell may have it
  // nearest: its distance to the cell's centre is within the nearest's plus
  // the diagonal. Only cells within reach of the outlier distance keep any.
  const double keep_within = config_.outlier_m + 0.5 * diagonal + bound;
  const double reach = keep_within + diagonal + 2.0 * bound;
  auto for_cells_near = [&](uint32_t shape, auto&& visit) {
    double sx0, sy0, sx1, sy1;
    if (shape < walls_.size()) {
      const Wall& w = walls_[shape];
      sx0 = std::min(w.ax, w.bx), sx1 = std::max(w.ax, w.bx);
      sy0 = std::min(w.ay, w.by), sy1 = std::max(w.ay, w.by);
    } else {
      const Circle& c = circles_[shape - walls_.size()];
      sx0 = c.cx - c.r, sx1 = c.cx + c.r, sy0 = c.cy - c.r, sy1 = c.cy + c.r;
    }
    const int i0 = std::max(0, static_cast<int>(std::floor((sx0 - reach - x0_) / cell_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((sx1 + reach - x0_) / cell_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((sy0 - reach - y0_) / cell_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((sy1 + reach - y0_) / cell_)));
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        double gx, gy;
        const double d =
            ShapeDistance(shape, x0_ + (i + 0.5) * cell_, y0_ + (j + 0.5) * cell_, gx, gy);
        visit(static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i), d);
      }
    }
  };
  std::vector<double> nearest(cells, std::numeric_limits<double>::infinity());
  for (uint32_t s = 0; s < shapes; ++s) {
    for_cells_near(s, [&](size_t c, double d) { nearest[c] = std::min(nearest[c], d); });
  }
  std::vector<uint32_t> counts(cells + 1, 0);
  auto is_candidate = [&](size_t c, double d) {
    return nearest[c] <= keep_within && d <= nearest[c] + diagonal + 2.0 * bound;
  };
  for (uint32_t s = 0; s < shapes; ++s) {
    for_cells_near(s, [&](size_t c, double d) {
      if (is_candidate(c, d)) ++counts[c];
    });
  }
  starts_.assign(cells + 1, 0);
  for (size_t c = 0; c < cells; ++c) starts_[c + 1] = starts_[c] + counts[c];
  candidates_.assign(starts_[cells], 0);
  std::fill(counts.begin(), counts.end(), 0);
  for (uint32_t s = 0; s < shapes; ++s) {
    for_cells_near(s, [&](size_t c, double d) {
      if (is_candidate(c, d)) candidates_[starts_[c] + counts[c]++] = s;
    });
  }
}

double TrackLocaliser::ShapeDistance(uint32_t index, double px, double py, double& gx, double& gy,
                                     double* t_out) const {
  if (index < walls_.size()) {
    const Wall& w = walls_[index];
    const double ex = w.bx - w.ax, ey = w.by - w.ay;
    const double length2 = ex * ex + ey * ey;
    const double t =
        length2 > 0.0 ? std::clamp(((px - w.ax) * ex + (py - w.ay) * ey) / length2, 0.0, 1.0) : 0.0;
    if (t_out != nullptr) *t_out = t;
    const double vx = px - (w.ax + t * ex), vy = py - (w.ay + t * ey);
    const double d = std::hypot(vx, vy);
    if (d > 1e-12) {
      gx = vx / d, gy = vy / d;
    } else {  // on the wall: either normal will do (the step is nil)
      const double l = std::sqrt(length2);
      gx = l > 0.0 ? -ey / l : 1.0, gy = l > 0.0 ? ex / l : 0.0;
    }
    return d;
  }
  const Circle& c = circles_[index - walls_.size()];
  const double vx = px - c.cx, vy = py - c.cy;
  const double n = std::hypot(vx, vy);
  if (n < 1e-12) {
    gx = 1.0, gy = 0.0;
    return c.r;
  }
  const double sign = n >= c.r ? 1.0 : -1.0;
  gx = sign * vx / n, gy = sign * vy / n;
  return std::abs(n - c.r);
}

bool TrackLocaliser::Field(double px, double py, double& distance, double& gx, double& gy) const {
  uint32_t shape;
  double t;
  return Nearest(px, py, distance, gx, gy, shape, t);
}

bool TrackLocaliser::Nearest(double px, double py, double& distance, double& gx, double& gy,
                             uint32_t& shape, double& t) const {
  const double fi = (px - x0_) / cell_, fj = (py - y0_) / cell_;
  if (!(fi >= 0.0 && fj >= 0.0 && fi < nx_ && fj < ny_)) return false;
  const size_t c = static_cast<size_t>(fj) * static_cast<size_t>(nx_) + static_cast<size_t>(fi);
  distance = std::numeric_limits<double>::infinity();
  for (uint32_t k = starts_[c]; k < starts_[c + 1]; ++k) {
    double x, y, along = 0.0;
    const double d = ShapeDistance(candidates_[k], px, py, x, y, &along);
    if (d < distance) distance = d, gx = x, gy = y, shape = candidates_[k], t = along;
  }
  return distance <= config_.outlier_m;
}

std::vector<MapFeature> TrackLocaliser::Map() const {
  std::vector<MapFeature> map;
  if (!config_.learn_map) {
    for (const Wall& w : walls_) {
      for (const Vec2& p : {Vec2(w.ax, w.ay), Vec2(w.bx, w.by)}) {
        if (std::none_of(map.begin(), map.end(), [&](const MapFeature& f) { return f.file == p; }))
          map.push_back({p, p});
      }
    }
    for (const Circle& c : circles_) map.push_back({Vec2(c.cx, c.cy), Vec2(c.cx, c.cy)});
    return map;
  }
  const auto offset = [&](size_t f) { return Vec2(offsets_(2 * f), offsets_(2 * f + 1)); };
  for (size_t f = 0; f < corners_.size(); ++f)
    map.push_back({corners_[f], corners_[f] + offset(f)});
  for (size_t p = 0; p < file_circles_.size(); ++p) {
    const Vec2 centre(file_circles_[p].cx, file_circles_[p].cy);
    map.push_back({centre, centre + offset(corners_.size() + p)});
  }
  return map;
}

Pose2 TrackLocaliser::OnFileMap(const Pose2& pose) const {
  if (!config_.learn_map) return pose;
  // Weighted 2-D Procrustes from the learnt features onto the file's:
  // centroids, then the rotation from the cross-covariance.
  const double inv_two_r2 = 1.0 / (2.0 * config_.local_radius_m * config_.local_radius_m);
  const auto feature = [&](size_t f, Vec2& file, Vec2& learnt) {
    file = f < corners_.size()
               ? corners_[f]
               : Vec2(file_circles_[f - corners_.size()].cx, file_circles_[f - corners_.size()].cy);
    learnt = file + Vec2(offsets_(2 * static_cast<Eigen::Index>(f)),
                         offsets_(2 * static_cast<Eigen::Index>(f) + 1));
  };
  const size_t features = corners_.size() + file_circles_.size();
  const Vec2 p(pose.x, pose.y);
  double weights = 0.0;
  Vec2 learnt_centre = Vec2::Zero(), file_centre = Vec2::Zero();
  Vec2 file, learnt;
  for (size_t f = 0; f < features; ++f) {
    feature(f, file, learnt);
    const double w = std::exp(-(learnt - p).squaredNorm() * inv_two_r2);
    weights += w;
    learnt_centre += w * learnt;
    file_centre += w * file;
  }
  if (weights < 1e-12) return pose;  // nothing of the track near: nothing to carry it by
  learnt_centre /= weights;
  file_centre /= weights;
  double cos_sum = 0.0, sin_sum = 0.0;
  for (size_t f = 0; f < features; ++f) {
    feature(f, file, learnt);
    const double w = std::exp(-(learnt - p).squaredNorm() * inv_two_r2);
    const Vec2 a = learnt - learnt_centre, b = file - file_centre;
    cos_sum += w * a.dot(b);
    sin_sum += w * (a.x() * b.y() - a.y() * b.x());
  }
  const double turn = std::atan2(sin_sum, cos_sum);
  const double c = std::cos(turn), s = std::sin(turn);
  const Vec2 d = p - learnt_centre;
  return {file_centre.x() + c * d.x() - s * d.y(), file_centre.y() + s * d.x() + c * d.y(),
          pose.heading + turn};
}

void TrackLocaliser::PlaceShapes(const Eigen::VectorXd& offsets) {
  for (size_t w = 0; w < walls_.size(); ++w) {
    const auto [a, b] = wall_corners_[w];
    walls_[w] = {file_walls_[w].ax + offsets(2 * a), file_walls_[w].ay + offsets(2 * a + 1),
                 file_walls_[w].bx + offsets(2 * b), file_walls_[w].by + offsets(2 * b + 1)};
  }
  const Eigen::Index first_post = 2 * static_cast<Eigen::Index>(corners_.size());
  for (size_t p = 0; p < circles_.size(); ++p) {
    const Eigen::Index i = first_post + 2 * static_cast<Eigen::Index>(p);
    circles_[p].cx = file_circles_[p].cx + offsets(i);
    circles_[p].cy = file_circles_[p].cy + offsets(i + 1);
  }
}

void TrackLocaliser::Reset(const Pose2& pose, double sd_m, double sd_rad) {
  pose_ = pose;
  cov_ = Diagonal(sd_m, sd_rad);
  if (config_.learn_map) {  // the map learnt stays; the pose is now known apart from it
    joint_cov_.topRows(3).setZero();
    joint_cov_.leftCols(3).setZero();
    joint_cov_.topLeftCorner<3, 3>() = ToMat(cov_);
  }
  started_ = true;
  have_odometry_ = false;
}

const Pose2& TrackLocaliser::Update(const Pose2& odometry, const RangeScan& scan, bool pressed) {
  if (!started_) {
    Reset(odometry, config_.initial_sd_m, config_.initial_sd_rad);
  }
  if (!have_odometry_) {
    last_odometry_ = odometry;
    have_odometry_ = true;
  } else {
    Motion(odometry, pressed);
  }
  Correct(scan);
  return pose_;
}

void TrackLocaliser::Motion(const Pose2& odometry, bool pressed) {
  // The increment in the frame of the previous odometry pose...
  const double dx = odometry.x - last_odometry_.x, dy = odometry.y - last_odometry_.y;
  const double c0 = std::cos(last_odometry_.heading), s0 = std::sin(last_odometry_.heading);
  const double forward = c0 * dx + s0 * dy, left = -s0 * dx + c0 * dy;
  const double turn = WrapAngle(odometry.heading - last_odometry_.heading);
  last_odometry_ = odometry;
  // ...applied in the estimate's.
  const double c = std::cos(pose_.heading), s = std::sin(pose_.heading);
  const double mx = c * forward - s * left, my = s * forward + c * left;
  pose_.x += mx;
  pose_.y += my;
  pose_.heading = WrapAngle(pose_.heading + turn);

  Mat3 f = Mat3::Identity();
  f(0, 2) = -my;
  f(1, 2) = mx;
  const double distance = std::hypot(forward, left);
  const double along = config_.along_per_m * distance +
                       (pressed ? config_.pressed_along_per_m * distance : 0.0) + config_.floor_m;
  const double across = config_.across_per_m * distance + config_.floor_m;
  const double heading = config_.heading_per_m * distance +
                         config_.heading_per_rad * std::abs(turn) + config_.floor_rad;
  const double ch = std::cos(pose_.heading), sh = std::sin(pose_.heading);
  Mat3 q = Mat3::Zero();
  const double a2 = along * along, b2 = across * across;
  q(0, 0) = ch * ch * a2 + sh * sh * b2;
  q(1, 1) = sh * sh * a2 + ch * ch * b2;
  q(0, 1) = q(1, 0) = ch * sh * (a2 - b2);
  q(2, 2) = heading * heading;
  FromMat(f * ToMat(cov_) * f.transpose() + q, cov_);
  if (config_.learn_map) {  // the pose's correlation with the map moves with it
    const Eigen::Index n = joint_cov_.rows();
    for (Eigen::Index j = 3; j < n; ++j) {
      joint_cov_(0, j) += f(0, 2) * joint_cov_(2, j);
      joint_cov_(1, j) += f(1, 2) * joint_cov_(2, j);
      joint_cov_(j, 0) = joint_cov_(0, j);
      joint_cov_(j, 1) = joint_cov_(1, j);
    }
    joint_cov_.topLeftCorner<3, 3>() = ToMat(cov_);
  }
}

bool TrackLocaliser::Agrees(const RangeScan& scan, double x, double y, double heading) const {
  // At the pose found, how many of the beams that met something end on the
  // map (within 3 sd of a wall or post)?
  int hits = 0, inliers = 0;
  ForEachHit(scan, x, y, heading, [&](double, double, double, double ex, double ey) {
    ++hits;
    double d, gx, gy;
    if (Field(ex, ey, d, gx, gy) && d <= 3.0 * config_.beam_sd) ++inliers;
  });
  return inliers >= config_.min_inlier_fraction * hits;
}

void TrackLocaliser::Correct(const RangeScan& scan) {
  beams_used_ = 0;
  if (scan.count <= 0 || starts_.empty()) return;
  if (config_.learn_map) return CorrectWithMap(scan);
  const Mat3 prior_cov = ToMat(cov_);
  const Mat3 prior_info = prior_cov.inverse();
  const Vec3 prior(pose_.x, pose_.y, pose_.heading);
  const double sd = config_.beam_sd;
  const double weight = 1.0 / (sd * sd);
  Vec3 x = prior;
  Mat3 info = prior_info;
  for (int iteration = 0; iteration < config_.iterations; ++iteration) {
    // Gauss-Newton on |x - prior|²_P⁻¹ + Σ w·d_i(x)²/sd²: info·step = b.
    info = prior_info;
    Vec3 offset = prior - x;
    offset.z() = WrapAngle(offset.z());
    Vec3 b = prior_info * offset;
    int used = 0;
    ForEachHit(scan, x.x(), x.y(), x.z(),
               [&](double r, double ca, double sa, double ex, double ey) {
                 double d, gx, gy;
                 if (!Field(ex, ey, d, gx, gy)) return;
                 const Vec3 j(gx, gy, r * (-gx * sa + gy * ca));
                 // Gated by what the prior allows this beam (3 sd), within the outlier distance.
                 const double predicted_sd = std::sqrt(j.dot(prior_cov * j) + sd * sd);
                 if (d > std::min(config_.outlier_m, 3.0 * predicted_sd)) return;
                 const double huber = d <= 2.0 * sd ? 1.0 : 2.0 * sd / d;
                 info.noalias() += (huber * weight) * j * j.transpose();
                 b -= (huber * weight * d) * j;
                 ++used;
               });
    beams_used_ = used;
    if (used == 0) break;
    const Vec3 step = info.ldlt().solve(b);
    x += step;
    x.z() = WrapAngle(x.z());
    if (std::abs(step.x()) + std::abs(step.y()) < 1e-5 && std::abs(step.z()) < 1e-5) break;
  }
  if (beams_used_ == 0) return;
  if (!Agrees(scan, x.x(), x.y(), x.z())) {
    // It disagrees with the map wherever the robot is: the odometry's pose stands.
    beams_used_ = 0;
    ++scans_refused_;
    return;
  }
  // A correction the map's own error can explain is taken slowly (see
  // LocaliserConfig::map_error_m); a larger one is the odometry's drift and
  // is taken whole. The scan's information S (the update's less the prior's)
  // is weighed by w: (P⁻¹ + w·S)·(x − prior) = w·S·(x_scan − prior).
  Vec3 correction = x - prior;
  correction.z() = WrapAngle(correction.z());
  const double tolerance = config_.map_error_m;
  const double size = std::hypot(correction.x(), correction.y()) +
                      config_.heading_lever_m * std::abs(correction.z());
  const double w =
      tolerance > 0.0 ? std::clamp(config_.within_map_error_weight + (size - tolerance) / tolerance,
                                   config_.within_map_error_weight, 1.0)
                      : 1.0;
  if (w < 1.0) {
    const Mat3 scan_info = info - prior_info;
    info = prior_info + w * scan_info;
    x = prior + info.ldlt().solve(w * scan_info * correction);
    x.z() = WrapAngle(x.z());
  }
  pose_ = {x.x(), x.y(), x.z()};
  FromMat(info.inverse(), cov_);
}

/// One learn_map update's linear system on the parameters the scan saw:
/// the pose (0-2) and the seen features' offsets (3 + 2·slot, x and y),
/// with each one's index in the joint state. Fixed-size: on the stack.
struct TrackLocaliser::SeenSystem {
  std::array<Eigen::Index, kMaxSeen> global{0, 1, 2};
  int features = 0;                              ///< the features seen (slots taken)
  Eigen::Index k = 3;                            ///< the parameters in use: 3 + 2·features
  MatSeen lambda = MatSeen(kMaxSeen, kMaxSeen);  ///< the scan's information Λ
  VecSeen g = VecSeen(kMaxSeen);                 ///< its gradient, linearised at the prior
  MatSeen p_seen = MatSeen(kMaxSeen, kMaxSeen);  ///< P_AA
  MatSeen m1 = MatSeen(kMaxSeen, kMaxSeen);      ///< I + Λ·P_AA
  VecSeen v = VecSeen(kMaxSeen);
  Eigen::PartialPivLU<MatSeen> lu = Eigen::PartialPivLU<MatSeen>(kMaxSeen);
};

void TrackLocaliser::CorrectWithMap(const RangeScan& scan) {
  // Correct's update with the map's offsets in the state. In covariance
  // form: with the scan's information Λ and gradient g (linearised at the
  // prior) on the k parameters it saw (the pose and the seen shapes'
  // offsets, A), the Gauss-Newton step from the prior is
  // −P_{·A}(I + Λ·P_AA)⁻¹·g and the covariance P − P_{·A}(I + Λ·P_AA)⁻¹Λ·P_{A·}
  // (the Woodbury identity on P⁻¹ + Λ): a k×k solve, no n×n one.
  const Vec3 prior(pose_.x, pose_.y, pose_.heading);
  prior_offsets_ = offsets_;
  SeenSystem system;
  Vec3 x = prior;
  for (int iteration = 0; iteration < config_.iterations; ++iteration) {
    beams_used_ = LineariseWithMap(scan, prior, x, system);
    if (beams_used_ == 0) break;
    step_offsets_ = offsets_;
    const Vec3 before = x;
    StepFromPrior(prior, system, x);
    PlaceShapes(offsets_);
    const double moved = (offsets_ - step_offsets_).cwiseAbs().maxCoeff();
    if (std::abs(x.x() - before.x()) + std::abs(x.y() - before.y()) < 1e-5 &&
        std::abs(WrapAngle(x.z() - before.z())) < 1e-5 && moved < 1e-5)
      break;
  }
  const auto keep_prior = [&] {
    offsets_ = prior_offsets_;
    PlaceShapes(offsets_);
  };
  if (beams_used_ == 0) return keep_prior();
  // The innovation gate, as Correct's, on the map as the update placed it.
  if (!Agrees(scan, x.x(), x.y(), x.z())) {
    beams_used_ = 0;
    ++scans_refused_;
    return keep_prior();
  }
  // No map-error band (LocaliserConfig::map_error_m): the map's error is in
  // the state. P −= P_{·A}·(I + Λ·P_AA)⁻¹·Λ·P_{A·} (the last iteration's
  // factors, as Correct's information), kept symmetric.
  const Eigen::Index n = joint_cov_.rows();
  const Eigen::Index k = system.k;
  const MatSeen gain = system.lu.solve(system.lambda.topLeftCorner(k, k));
  seen_gain_.leftCols(k).noalias() = seen_cov_.leftCols(k).lazyProduct(gain);
  joint_cov_ -= seen_gain_.leftCols(k).lazyProduct(seen_cov_.leftCols(k).transpose());
  for (Eigen::Index a = 0; a < n; ++a) {
    for (Eigen::Index b = a + 1; b < n; ++b) {
      const double mean = 0.5 * (joint_cov_(a, b) + joint_cov_(b, a));
      joint_cov_(a, b) = joint_cov_(b, a) = mean;
    }
  }
  pose_ = {x.x(), x.y(), x.z()};
  FromMat(joint_cov_.topLeftCorner<3, 3>(), cov_);
}

int TrackLocaliser::LineariseWithMap(const RangeScan& scan, const Eigen::Vector3d& prior,
                                     const Eigen::Vector3d& x, SeenSystem& s) {
  const double sd = config_.beam_sd;
  const double weight = 1.0 / (sd * sd);
  const auto walls = static_cast<uint32_t>(walls_.size());
  const auto first_post = static_cast<int>(corners_.size());
  std::fill(slot_.begin(), slot_.end(), -1);
  s.features = 0;
  s.lambda.setZero();
  s.g.setZero();
  int used = 0;
  ForEachHit(scan, x.x(), x.y(), x.z(), [&](double r, double ca, double sa, double ex, double ey) {
    double d, gx, gy, t;
    uint32_t shape;
    if (!Nearest(ex, ey, d, gx, gy, shape, t)) return;
    // The beam's Jacobian: on the pose, and on its shape's offsets (a
    // wall's corners by −(1−t)·n and −t·n, a post's centre by −n).
    std::array<Eigen::Index, 7> local{0, 1, 2};
    std::array<double, 7> j{gx, gy, r * (-gx * sa + gy * ca)};
    int m = 3;
    const auto add_feature = [&](int feature, double share) {
      int& slot = slot_[static_cast<size_t>(feature)];
      if (slot < 0) {
        if (s.features == kMaxSeenFeatures) return;  // held where it is learnt
        slot = s.features++;
        s.global[static_cast<size_t>(3 + 2 * slot)] = 3 + 2 * feature;
        s.global[static_cast<size_t>(4 + 2 * slot)] = 4 + 2 * feature;
      }
      local[static_cast<size_t>(m)] = 3 + 2 * slot;
      local[static_cast<size_t>(m + 1)] = 4 + 2 * slot;
      j[static_cast<size_t>(m)] = -share * gx;
      j[static_cast<size_t>(m + 1)] = -share * gy;
      m += 2;
    };
    if (shape < walls) {
      add_feature(static_cast<int>(wall_corners_[shape][0]), 1.0 - t);
      add_feature(static_cast<int>(wall_corners_[shape][1]), t);
    } else {
      add_feature(first_post + static_cast<int>(shape - walls), 1.0);
    }
    const auto at = [&](int a) {
      return s.global[static_cast<size_t>(local[static_cast<size_t>(a)])];
    };
    const auto ja = [&](int a) { return j[static_cast<size_t>(a)]; };
    // Gated by what the prior allows this beam (3 sd), within the outlier distance.
    double jpj = 0.0;
    for (int a = 0; a < m; ++a) {
      for (int b = 0; b < m; ++b) jpj += ja(a) * ja(b) * joint_cov_(at(a), at(b));
    }
    const double predicted_sd = std::sqrt(jpj + sd * sd);
    if (d > std::min(config_.outlier_m, 3.0 * predicted_sd)) return;
    const double huber = d <= 2.0 * sd ? 1.0 : 2.0 * sd / d;
    // The residual linearised at the prior: d + J·(prior − x).
    double residual = d + j[0] * (prior.x() - x.x()) + j[1] * (prior.y() - x.y()) +
                      j[2] * WrapAngle(prior.z() - x.z());
    for (int a = 3; a < m; ++a) {
      const Eigen::Index o = at(a) - 3;
      residual += ja(a) * (prior_offsets_(o) - offsets_(o));
    }
    for (int a = 0; a < m; ++a) {
      const Eigen::Index la = local[static_cast<size_t>(a)];
      s.g(la) += huber * weight * ja(a) * residual;
      for (int b = 0; b < m; ++b)
        s.lambda(la, local[static_cast<size_t>(b)]) += huber * weight * ja(a) * ja(b);
    }
    ++used;
  });
  if (used > 0) s.k = 3 + 2 * s.features;
  return used;
}

void TrackLocaliser::StepFromPrior(const Eigen::Vector3d& prior, SeenSystem& s,
                                   Eigen::Vector3d& pose) {
  const Eigen::Index n = joint_cov_.rows();
  const Eigen::Index k = s.k;
  for (Eigen::Index l = 0; l < k; ++l)
    seen_cov_.col(l) = joint_cov_.col(s.global[static_cast<size_t>(l)]);
  for (Eigen::Index a = 0; a < k; ++a) {
    for (Eigen::Index b = 0; b < k; ++b)
      s.p_seen(a, b) = seen_cov_(s.global[static_cast<size_t>(a)], b);
  }
  // The step from the prior, into pose and offsets.
  s.m1.setIdentity(k, k);
  s.m1.noalias() += s.lambda.topLeftCorner(k, k) * s.p_seen.topLeftCorner(k, k);
  s.lu.compute(s.m1);
  s.v = s.lu.solve(s.g.head(k));
  for (Eigen::Index i = 0; i < n; ++i) {
    double y = 0.0;
    for (Eigen::Index l = 0; l < k; ++l) y -= seen_cov_(i, l) * s.v(l);
    if (i < 3) {
      pose(i) = prior(i) + y;
    } else {
      offsets_(i - 3) = prior_offsets_(i - 3) + y;
    }
  }
  pose.z() = WrapAngle(pose.z());
  for (Eigen::Index f = 0; f < offsets_.size(); f += 2) {  // within the grid's margin
    const double norm = std::hypot(offsets_(f), offsets_(f + 1));
    if (norm > config_.offset_bound_m) offsets_.segment<2>(f) *= config_.offset_bound_m / norm;
  }
}

}  // namespace haptel::mediator
