#include "haptel/mediator/blimp/course_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace haptel::mediator {

namespace {

double Radians(double deg) { return deg * std::numbers::pi / 180.0; }

/// A point in a building's own frame (its footprint axis-aligned, centred).
Eigen::Vector2d Local(const BlimpBuildingSpec& b, const Eigen::Vector2d& p) {
  const double c = std::cos(Radians(b.yaw_deg)), s = std::sin(Radians(b.yaw_deg));
  const Eigen::Vector2d d = p - Eigen::Vector2d(b.centre[0], b.centre[1]);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
}

double BoxDistance(const Eigen::Vector2d& half, const Eigen::Vector2d& local) {
  return (local.cwiseAbs() - half).cwiseMax(0.0).norm();
}

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double length2 = ab.squaredNorm();
  const double t = length2 > 0.0 ? std::clamp((p - a).dot(ab) / length2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

/// Whether the segment a–b (local frame) meets the box |x| <= half.
bool SegmentMeetsBox(const Eigen::Vector2d& half, const Eigen::Vector2d& a,
                     const Eigen::Vector2d& b) {
  double t_in = 0.0, t_out = 1.0;
  const Eigen::Vector2d d = b - a;
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(d[axis]) < 1e-12) {
      if (std::abs(a[axis]) > half[axis]) return false;
      continue;
    }
    double t0 = (-half[axis] - a[axis]) / d[axis], t1 = (half[axis] - a[axis]) / d[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
    if (t_in > t_out) return false;
  }
  return true;
}

}  // namespace

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

double FootprintDistance(const BlimpBuildingSpec& building, double x, double y) {
  const Eigen::Vector2d half(building.size[0] / 2, building.size[1] / 2);
  return BoxDistance(half, Local(building, {x, y}));
}

double FootprintDistance(const BlimpBuildingSpec& building, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d half(building.size[0] / 2, building.size[1] / 2);
  const Eigen::Vector2d la = Local(building, a), lb = Local(building, b);
  if (SegmentMeetsBox(half, la, lb)) return 0.0;
  double best = std::min(BoxDistance(half, la), BoxDistance(half, lb));
  for (int sx = -1; sx <= 1; sx += 2) {
    for (int sy = -1; sy <= 1; sy += 2) {
      best = std::min(best, PointSegmentDistance({sx * half.x(), sy * half.y()}, la, lb));
    }
  }
  return best;
}

}  // namespace haptel::mediator
