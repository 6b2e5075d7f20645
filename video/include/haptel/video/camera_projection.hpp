#pragma once
/// @file The robot camera's projection: a level pinhole camera
/// `mount_height` above the floor at the vehicle's position, looking along
/// its heading, with the horizontal field of view and picture size of the
/// vehicle file's `camera:` section. SyntheticCamera draws the simulated
/// picture with it; the operator's predictive display projects the ghost
/// into the received picture with the same numbers, so the two agree.
///
/// Camera coordinates: depth d along the heading, lateral l to the left,
/// height z above the floor. A point projects to column u = cx - f*l/d and
/// row v = cy + f*(h - z)/d, with f = (width/2) / tan(fov/2) and (cx, cy)
/// the picture's centre: the camera is level, so the horizon is the middle
/// row (continuous coordinates: pixel i covers [i, i+1)).
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/geometry2d.hpp"

namespace haptel::video {

/// A level camera at a pose on the floor.
struct LevelCamera {
  /// Nearer than this (m of depth) nothing is drawn: the near plane.
  static constexpr double kNear = 0.02;

  double x = 0, y = 0, cos_h = 1, sin_h = 0;  ///< camera position (world, m) and heading
  double f = 1, cx = 0, cy = 0, h = 0;        ///< focal length (px), principal point, mount height
  double tan_half = 1;  ///< tangent of half the horizontal FOV, widened by a pixel (clipping)

  /// The camera of `config` at (x, y) looking along `heading` (rad).
  static LevelCamera At(const CameraConfig& config, double x, double y, double heading) {
    LevelCamera c;
    c.x = x;
    c.y = y;
    c.cos_h = std::cos(heading);
    c.sin_h = std::sin(heading);
    const double half_fov = config.fov_deg * std::numbers::pi / 360.0;
    c.f = (config.width / 2.0) / std::tan(half_fov);
    c.cx = config.width / 2.0;
    c.cy = config.height / 2.0;
    c.h = config.mount_height;
    // Widened by a pixel so that clipped geometry reaches the picture's border.
    c.tan_half = (config.width / 2.0 + 1.0) / c.f;
    return c;
  }

  /// A world point's depth and lateral offset.
  void ToCamera(const Vec2& p, double& d, double& l) const {
    const double dx = p.x() - x;
    const double dy = p.y() - y;
    d = dx * cos_h + dy * sin_h;
    l = -dx * sin_h + dy * cos_h;
  }
  double U(double d, double l) const { return cx - f * l / d; }
  double V(double d, double z) const { return cy + f * (h - z) / d; }

  /// Clips the floor segment p0-p1 (camera coordinates: d, l) to the part in
  /// front of the near plane and inside the horizontal field of view. False
  /// if nothing is left.
  bool ClipSegment(cv::Vec2d& p0, cv::Vec2d& p1) const {
    const auto clip = [&](double g0, double g1) {  // keeps g >= 0
      if (g0 < 0 && g1 < 0) return false;
      if (g0 < 0) {
        p0 = p0 + (p1 - p0) * (g0 / (g0 - g1));
      } else if (g1 < 0) {
        p1 = p1 + (p0 - p1) * (g1 / (g1 - g0));
      }
      return true;
    };
    const double t = tan_half;
    return clip(p0[0] - kNear, p1[0] - kNear) && clip(t * p0[0] - p0[1], t * p1[0] - p1[1]) &&
           clip(t * p0[0] + p0[1], t * p1[0] + p1[1]);
  }

  /// Clips the convex floor polygon `poly` (camera coordinates), in place,
  /// the same way (Sutherland-Hodgman); `scratch` is working space. Both
  /// keep their capacity: a caller that reuses them allocates nothing.
  void ClipPolygon(std::vector<cv::Vec2d>& poly, std::vector<cv::Vec2d>& scratch) const {
    const double t = tan_half;
    const cv::Vec3d planes[3] = {cv::Vec3d(1, 0, -kNear), cv::Vec3d(t, -1, 0), cv::Vec3d(t, 1, 0)};
    for (const cv::Vec3d& pl : planes) {
      scratch.clear();
      const auto g = [&](const cv::Vec2d& p) { return pl[0] * p[0] + pl[1] * p[1] + pl[2]; };
      for (size_t i = 0; i < poly.size(); ++i) {
        const cv::Vec2d& a = poly[i];
        const cv::Vec2d& b = poly[(i + 1) % poly.size()];
        const double ga = g(a);
        const double gb = g(b);
        if (ga >= 0) scratch.push_back(a);
        if ((ga >= 0) != (gb >= 0)) scratch.push_back(a + (b - a) * (ga / (ga - gb)));
      }
      poly.swap(scratch);
      if (poly.empty()) break;
    }
  }
};

}  // namespace haptel::video
