#include "haptel/mediator/predictive_display.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "haptel/video/camera_projection.hpp"

namespace haptel::mediator {

namespace {

/// The ghost's height for `camera` (predictive_display.hpp): the top front
/// edge of a ghost with no lead, `radius` ahead, is on the picture's bottom
/// row when mount height - ghost height = (cy / f) * radius.
double GhostHeight(const CameraConfig& camera, double radius) {
  const video::LevelCamera lens = video::LevelCamera::At(camera, 0.0, 0.0, 0.0);
  const double hidden = lens.h - lens.cy / lens.f * radius;
  return std::clamp(PredictiveDisplay::kHeightMargin * hidden, 0.0, lens.h);
}

}  // namespace

BodySilhouette::BodySilhouette() {
  footprint_.reserve(2 * kSides);
  scratch_.reserve(2 * kSides);
  corners_.reserve(4 * kSides);
  hull_.reserve(4 * kSides);
}

int BodySilhouette::Make(const video::LevelCamera& camera, double width, double height_px, double x,
                         double y, double radius, double height,
                         std::array<view::PicturePoint, view::Prediction::kOutlineMax>& out) {
  footprint_.clear();
  for (int k = 0; k < kSides; ++k) {
    const double a = 2.0 * std::numbers::pi * k / kSides;
    double d = 0, l = 0;
    camera.ToCamera(Vec2(x + radius * std::cos(a), y + radius * std::sin(a)), d, l);
    footprint_.emplace_back(d, l);
  }
  camera.ClipPolygon(footprint_, scratch_);
  if (footprint_.size() < 3) return 0;
  corners_.clear();
  for (const cv::Vec2d& p : footprint_) {
    for (const double z : {0.0, height}) {
      corners_.emplace_back(static_cast<float>(camera.U(p[0], p[1]) / width),
                            static_cast<float>(camera.V(p[0], z) / height_px));
    }
  }
  cv::convexHull(corners_, hull_);
  const int count = std::min(static_cast<int>(hull_.size()), view::Prediction::kOutlineMax);
  for (int i = 0; i < count; ++i) {
    out[static_cast<size_t>(i)] = {hull_[static_cast<size_t>(i)].x,
                                   hull_[static_cast<size_t>(i)].y};
  }
  return count;
}

PredictiveDisplay::PredictiveDisplay(const CameraConfig& camera, double body_radius)
    : camera_(camera), radius_m_(body_radius), ghost_height_m_(GhostHeight(camera, body_radius)) {}

void PredictiveDisplay::Make(const PredictedPose& camera_pose,
                             const std::vector<PredictedPose>& path, double one_way_delay_s,
                             view::Prediction& out) {
  out.outline_count = 0;
  out.path_count = 0;
  out.map_path_count = 0;
  out.shown = !path.empty();
  if (!out.shown) return;
  const auto cam =
      video::LevelCamera::At(camera_, camera_pose.x, camera_pose.y, camera_pose.heading);
  const double w = camera_.width, h = camera_.height;
  const auto picture = [&](double d, double l, double z) {
    return view::PicturePoint{static_cast<float>(cam.U(d, l) / w),
                              static_cast<float>(cam.V(d, z) / h)};
  };

  // The ghost: the body's silhouette where the model says it is now.
  const PredictedPose& now = path.front();
  out.outline_count =
      silhouette_.Make(cam, w, h, now.x, now.y, radius_m_, ghost_height_m_, out.outline);

  // The path ahead on the floor, each stretch clipped the same way.
  for (size_t i = 1; i < path.size() && out.path_count < view::Prediction::kPathMax; ++i) {
    cv::Vec2d a, b;
    cam.ToCamera(Vec2(path[i - 1].x, path[i - 1].y), a[0], a[1]);
    cam.ToCamera(Vec2(path[i].x, path[i].y), b[0], b[1]);
    if (!cam.ClipSegment(a, b)) continue;
    out.path[static_cast<size_t>(out.path_count++)] = {picture(a[0], a[1], 0.0),
                                                       picture(b[0], b[1], 0.0)};
  }

  // The map.
  const auto map_pose = [](const PredictedPose& p) {
    return view::MapPose{static_cast<float>(p.x), static_cast<float>(p.y),
                         static_cast<float>(p.heading)};
  };
  out.reported = map_pose(camera_pose);
  out.predicted = map_pose(now);
  out.map_path_count =
      static_cast<int>(std::min(path.size(), static_cast<size_t>(view::Prediction::kPathMax)));
  for (int i = 0; i < out.map_path_count; ++i)
    out.map_path[static_cast<size_t>(i)] = map_pose(path[static_cast<size_t>(i)]);
  out.body_radius = static_cast<float>(radius_m_);
  out.one_way_delay_s = static_cast<float>(one_way_delay_s);
}

view::TrackMap TrackMapOf(const Track& track) {
  view::TrackMap map;
  const auto line = [](const Vec2& a, const Vec2& b) {
    return view::TrackMap::Line{a.x(), a.y(), b.x(), b.y()};
  };
  for (const Segment2& wall : track.walls()) map.walls.push_back(line(wall.a, wall.b));
  // The start line reaches a little past the walls; trimmed to the corridor
  // as the camera draws it.
  const Segment2& start = track.start_line();
  const Vec2 mid = (start.a + start.b) / 2;
  const double length = (start.b - start.a).norm();
  if (length > 0) {
    const Vec2 half =
        (start.b - start.a) / length * (std::min(length, track.config().corridor_width) / 2);
    map.start = line(mid - half, mid + half);
  }
  const auto same = [](const Vec2& a, const Vec2& b) { return (a - b).squaredNorm() < 1e-12; };
  for (const Gate& gate : track.gates()) map.gates.push_back(line(gate.left_post, gate.right_post));
  for (const CircleObstacle& c : track.round_obstacles()) {
    view::TrackMap::Post post{c.center.x(), c.center.y(), c.radius,
                              view::TrackMap::PostKind::kObstacle};
    for (const Gate& gate : track.gates()) {
      if (same(c.center, gate.left_post)) post.kind = view::TrackMap::PostKind::kLeft;
      if (same(c.center, gate.right_post)) post.kind = view::TrackMap::PostKind::kRight;
    }
    map.posts.push_back(post);
  }
  return map;
}

void MakeBlimpPrediction(const BlimpPredictedPose& reported,
                         const std::vector<BlimpPredictedPose>& path, double hull_length,
                         double one_way_delay_s, view::Prediction& out) {
  out.outline_count = 0;
  out.path_count = 0;
  out.map_path_count = 0;
  out.heights = true;
  out.shown = !path.empty();
  if (!out.shown) return;
  const auto map_pose = [](const BlimpPredictedPose& p) {
    return view::MapPose{static_cast<float>(p.position.x()), static_cast<float>(p.position.y()),
                         static_cast<float>(p.yaw), static_cast<float>(p.position.z())};
  };
  out.reported = map_pose(reported);
  out.predicted = map_pose(path.front());
  out.map_path_count =
      static_cast<int>(std::min(path.size(), static_cast<size_t>(view::Prediction::kPathMax)));
  for (int i = 0; i < out.map_path_count; ++i)
    out.map_path[static_cast<size_t>(i)] = map_pose(path[static_cast<size_t>(i)]);
  out.body_radius = static_cast<float>(hull_length / 2);
  out.one_way_delay_s = static_cast<float>(one_way_delay_s);
}

view::TrackMap CourseMapOf(const BlimpCourseConfig& course) {
  view::TrackMap map;
  constexpr double kDeg = std::numbers::pi / 180.0;
  for (const BlimpGateSpec& gate : course.gates) {
    // Across the direction of travel: left of it is +90°.
    const double a = gate.heading_deg * kDeg;
    const double half = gate.width / 2;
    const double lx = gate.centre[0] - half * std::sin(a), ly = gate.centre[1] + half * std::cos(a);
    const double rx = gate.centre[0] + half * std::sin(a), ry = gate.centre[1] - half * std::cos(a);
    map.gates.push_back({lx, ly, rx, ry});
    map.posts.push_back({lx, ly, 0.1, view::TrackMap::PostKind::kLeft});
    map.posts.push_back({rx, ry, 0.1, view::TrackMap::PostKind::kRight});
    char text[48];
    std::snprintf(text, sizeof text, "%.1f-%.1f m", gate.centre[2] - gate.height / 2,
                  gate.centre[2] + gate.height / 2);
    map.labels.push_back({gate.centre[0], gate.centre[1], text});
  }
  for (const BlimpBuildingSpec& b : course.buildings) {
    const double a = b.yaw_deg * kDeg, c = std::cos(a), s = std::sin(a);
    const double hx = b.size[0] / 2, hy = b.size[1] / 2;
    const auto corner = [&](double u, double v) {
      return Vec2(b.centre[0] + c * u - s * v, b.centre[1] + s * u + c * v);
    };
    const Vec2 k[4] = {corner(-hx, -hy), corner(hx, -hy), corner(hx, hy), corner(-hx, hy)};
    for (int i = 0; i < 4; ++i) {
      const Vec2& p = k[i];
      const Vec2& q = k[(i + 1) % 4];
      map.walls.push_back({p.x(), p.y(), q.x(), q.y()});
    }
  }
  // The start: a short line across the blimp's heading where it rests.
  const double h = course.start.heading_deg * kDeg;
  const double sx = course.start.position[0], sy = course.start.position[1];
  map.start = {sx - 0.5 * std::sin(h), sy + 0.5 * std::cos(h), sx + 0.5 * std::sin(h),
               sy - 0.5 * std::cos(h)};
  map.posts.push_back({course.landing.centre[0], course.landing.centre[1], course.landing.radius,
                       view::TrackMap::PostKind::kLanding});
  return map;
}

}  // namespace haptel::mediator
