#include "haptel/config/blimp_course_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/core/geometry2d.hpp"

namespace haptel {

BlimpGateFrame MakeGateFrame(const BlimpGateSpec& gate) {
  BlimpGateFrame f;
  const double h = Radians(gate.heading_deg);
  f.centre = {gate.centre[0], gate.centre[1], gate.centre[2]};
  f.forward = {std::cos(h), std::sin(h), 0.0};
  f.left = {-std::sin(h), std::cos(h), 0.0};
  f.half_width = gate.width / 2;
  f.half_height = gate.height / 2;
  return f;
}

std::vector<BlimpGateFrame> MakeGateFrames(const BlimpCourseConfig& course) {
  std::vector<BlimpGateFrame> frames;
  frames.reserve(course.gates.size());
  for (const BlimpGateSpec& g : course.gates) frames.push_back(MakeGateFrame(g));
  return frames;
}

BlimpGateCrossing ClassifyCrossing(const BlimpGateFrame& gate, const Eigen::Vector3d& p,
                                   double near_widths) {
  const Eigen::Vector3d d = p - gate.centre;
  const double across = d.dot(gate.left), up = d.z();
  if (std::abs(across) <= gate.half_width && std::abs(up) <= gate.half_height)
    return BlimpGateCrossing::kPassed;
  if (std::hypot(across, up) <= near_widths * 2.0 * gate.half_width)
    return BlimpGateCrossing::kMissed;
  return BlimpGateCrossing::kIgnored;
}

std::optional<BlimpGatePass> CrossGate(const BlimpGateFrame& gate, const Eigen::Vector3d& p0,
                                       const Eigen::Vector3d& p1) {
  const double s0 = gate.Along(p0), s1 = gate.Along(p1);
  if (!(s0 < 0.0 && s1 >= 0.0)) return std::nullopt;
  const double f = s0 / (s0 - s1);
  return BlimpGatePass{f, ClassifyCrossing(gate, p0 + f * (p1 - p0))};
}

BlimpFootprint::BlimpFootprint(const BlimpBuildingSpec& b)
    : centre_(b.centre[0], b.centre[1]),
      half_(b.size[0] / 2, b.size[1] / 2),
      cos_yaw_(std::cos(Radians(b.yaw_deg))),
      sin_yaw_(std::sin(Radians(b.yaw_deg))),
      height_(b.height) {}

Eigen::Vector2d BlimpFootprint::Local(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d d = p - centre_;
  return {cos_yaw_ * d.x() + sin_yaw_ * d.y(), -sin_yaw_ * d.x() + cos_yaw_ * d.y()};
}

double BlimpFootprint::Distance(const Eigen::Vector2d& p) const {
  return (Local(p).cwiseAbs() - half_).cwiseMax(0.0).norm();
}

bool BlimpFootprint::MeetsLocal(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  // Slab clipping of the segment against |x| <= half.
  double t_in = 0.0, t_out = 1.0;
  const Eigen::Vector2d d = b - a;
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(d[axis]) < 1e-12) {
      if (std::abs(a[axis]) > half_[axis]) return false;
      continue;
    }
    double t0 = (-half_[axis] - a[axis]) / d[axis], t1 = (half_[axis] - a[axis]) / d[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
    if (t_in > t_out) return false;
  }
  return true;
}

bool BlimpFootprint::Meets(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  return MeetsLocal(Local(a), Local(b));
}

double BlimpFootprint::Distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  const Eigen::Vector2d la = Local(a), lb = Local(b);
  if (MeetsLocal(la, lb)) return 0.0;
  const auto box_distance = [&](const Eigen::Vector2d& p) {
    return (p.cwiseAbs() - half_).cwiseMax(0.0).norm();
  };
  double best = std::min(box_distance(la), box_distance(lb));
  for (int sx = -1; sx <= 1; sx += 2) {
    for (int sy = -1; sy <= 1; sy += 2) {
      const Eigen::Vector2d corner(sx * half_.x(), sy * half_.y());
      best = std::min(best, (ClosestPointOnSegment({la, lb}, corner) - corner).norm());
    }
  }
  return best;
}

std::vector<BlimpFootprint> MakeFootprints(const BlimpCourseConfig& course) {
  std::vector<BlimpFootprint> footprints;
  footprints.reserve(course.buildings.size());
  for (const BlimpBuildingSpec& b : course.buildings) footprints.emplace_back(b);
  return footprints;
}

bool OnLandingGround(const BlimpCourseConfig& course, const Eigen::Vector3d& p, double start_z) {
  const double dx = p.x() - course.landing.centre[0], dy = p.y() - course.landing.centre[1];
  return std::hypot(dx, dy) <= course.landing.radius && p.z() < start_z + course.takeoff_height;
}

}  // namespace haptel
