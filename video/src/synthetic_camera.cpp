#include "haptel/video/synthetic_camera.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/video/camera_projection.hpp"

// How the view is drawn, back to front:
//  1. sky (rows above the horizon): a vertical blue gradient;
//  2. floor (rows below): brown, hazier with distance, with a faint 0.5 m
//     checkerboard close to the camera so that motion is visible;
//  3. the start line, a white strip on the floor;
//  4. walls and round obstacles, sorted far to near (painter's algorithm):
//     walls are 0.25 m panels cut into short pieces (so that sorting by piece
//     distance works and shading varies along a wall), posts and obstacles are
//     0.3 m bars as wide as the cylinder's silhouette.
// The camera is level, so the horizon is the middle row; its projection
// (camera coordinates, the clipping to what it sees) is LevelCamera's, in
// camera_projection.hpp, which the operator's predictive display shares.

namespace haptel::video {

CameraPose MountedPose(const CameraPose& body, const CameraConfig& camera, const CameraAim& aim) {
  constexpr double kRadPerDeg = 0.017453292519943295;
  CameraPose p = body;
  const double c = std::cos(body.heading), s = std::sin(body.heading);
  p.x += camera.mount_forward * c - camera.mount_left * s;
  p.y += camera.mount_forward * s + camera.mount_left * c;
  p.pan = camera.mount_yaw_deg * kRadPerDeg + aim.pan;
  p.tilt = camera.mount_pitch_deg * kRadPerDeg + aim.tilt;
  p.zoom = aim.zoom;
  return p;
}

namespace {

constexpr double kNear = LevelCamera::kNear;  // near plane, m
constexpr double kWallHeight = 0.25;          // m
constexpr double kPostHeight = 0.3;           // m, gate posts and round obstacles
constexpr double kWallPiece = 0.15;           // m, wall pieces for sorting and shading
constexpr double kTile = 0.5;                 // m, floor checkerboard
constexpr double kStartLineWidth = 0.04;      // m
constexpr double kMaxPoseCoord = 1e6;         // m; poses farther out are rendered as invalid
constexpr double kMaxPixelCoord = 1e6;        // px; drawing coordinates are clamped to this
constexpr int kShift = 4;                     // sub-pixel bits for fillConvexPoly
constexpr double kOne = 1 << kShift;

// Palette (BGR).
const cv::Vec3d kSkyTop(225, 170, 115);
const cv::Vec3d kSkyHorizon(245, 225, 200);
const cv::Vec3d kFloor(80, 100, 122);
const cv::Vec3d kHaze(170, 170, 170);
const cv::Vec3d kWall(195, 212, 226);
const cv::Vec3d kLeftPost(40, 40, 225);
const cv::Vec3d kRightPost(50, 200, 40);
const cv::Vec3d kObstacle(0, 140, 255);
const cv::Vec3d kStartLine(245, 245, 245);
const cv::Vec3b kInvalid(60, 60, 60);

cv::Vec3b ToPixel(const cv::Vec3d& c) {
  return {cv::saturate_cast<uint8_t>(c[0]), cv::saturate_cast<uint8_t>(c[1]),
          cv::saturate_cast<uint8_t>(c[2])};
}

/// Darkening with distance for walls, posts and floor markings.
double DistanceShade(double dist) { return 0.45 + 0.55 * std::exp(-dist / 5.0); }

/// Pixel-centre coordinates for OpenCV drawing with kShift fractional bits.
cv::Point ToDrawPoint(double u, double v) {
  const auto fix = [](double c) {
    return static_cast<int>(
        std::lround(std::clamp(c - 0.5, -kMaxPixelCoord, kMaxPixelCoord) * kOne));
  };
  return {fix(u), fix(v)};
}

/// A wall piece or a bar, ready to draw.
struct Item {
  double dist = 0.0;  // from the camera, for sorting
  bool is_wall = true;
  cv::Point quad[4];      // wall piece
  double u0 = 0, u1 = 0;  // bar columns (left, right)
  double v0 = 0, v1 = 0;  // bar rows (top, bottom)
  cv::Vec3d colour;
};

void DrawSky(cv::Mat& image, double cy) {
  const int rows = std::clamp(static_cast<int>(std::ceil(cy - 0.5)), 0, image.rows);
  for (int r = 0; r < rows; ++r) {
    const double t = (r + 0.5) / cy;  // 0 at the top, 1 at the horizon
    const cv::Vec3b c = ToPixel(kSkyTop * (1 - t) + kSkyHorizon * t);
    cv::Vec3b* row = image.ptr<cv::Vec3b>(r);
    std::fill(row, row + image.cols, c);
  }
}

void DrawFloor(cv::Mat& image, const LevelCamera& view) {
  // Tile parity is counted from the tile holding the camera, so that the
  // per-pixel arithmetic stays small whatever the pose.
  const double tx = std::floor(view.x / kTile);
  const double ty = std::floor(view.y / kTile);
  const int base_parity = static_cast<int>(std::fmod(std::abs(tx + ty), 2.0));
  const double ox = view.x - tx * kTile;  // camera within its tile, [0, kTile)
  const double oy = view.y - ty * kTile;
  const int first = std::clamp(static_cast<int>(std::ceil(view.cy - 0.5)), 0, image.rows);
  for (int r = first; r < image.rows; ++r) {
    const double below = r + 0.5 - view.cy;  // > 0
    const double depth = view.f * view.h / below;
    const double haze = 1.0 - std::exp(-depth / 12.0);
    const cv::Vec3d base = kFloor * (1 - haze) + kHaze * haze;
    // Checker contrast, faded out where a tile is only a few rows tall.
    const double tile_rows = view.f * view.h * kTile / (depth * depth);
    const double contrast = 10.0 * std::clamp((tile_rows - 2.0) / 6.0, 0.0, 1.0);
    cv::Vec3b* row = image.ptr<cv::Vec3b>(r);
    if (contrast <= 0.0) {
      std::fill(row, row + image.cols, ToPixel(base));
      continue;
    }
    const cv::Vec3b light = ToPixel(base + cv::Vec3d::all(contrast));
    const cv::Vec3b dark = ToPixel(base - cv::Vec3d::all(contrast));
    // Floor point of column u: depth ahead, (cx - u - 0.5) * depth / f to the left.
    const double k = depth / view.f;
    const double fx = view.cos_h * depth, fy = view.sin_h * depth;  // forward
    const double lx = -view.sin_h * k, ly = view.cos_h * k;         // left per pixel
    for (int u = 0; u < image.cols; ++u) {
      const double lat = view.cx - (u + 0.5);
      const double wx = (ox + fx + lx * lat) / kTile;
      const double wy = (oy + fy + ly * lat) / kTile;
      const long parity = static_cast<long>(std::floor(wx)) + static_cast<long>(std::floor(wy));
      row[u] = ((parity + base_parity) & 1) ? dark : light;
    }
  }
}

void DrawStartLine(cv::Mat& image, const LevelCamera& view, const Segment2& line, double corridor) {
  // The start line reaches a little past the walls; trim it to the corridor.
  const Vec2 mid = (line.a + line.b) / 2;
  const Vec2 along = line.b - line.a;
  const double len = along.norm();
  if (len <= 0) return;
  const Vec2 dir = along / len;
  const Vec2 across(-dir.y(), dir.x());
  const double half = std::min(len, corridor) / 2;
  const double w = kStartLineWidth / 2;
  std::vector<cv::Vec2d> poly;
  const Vec2 corners[4] = {mid - dir * half - across * w, mid + dir * half - across * w,
                           mid + dir * half + across * w, mid - dir * half + across * w};
  for (const Vec2& p : corners) {
    double d = 0, l = 0;
    view.ToCamera(p, d, l);
    poly.emplace_back(d, l);
  }
  std::vector<cv::Vec2d> scratch;
  view.ClipPolygon(poly, scratch);
  if (poly.size() < 3) return;
  std::vector<cv::Point> pts;
  for (const cv::Vec2d& p : poly) pts.push_back(ToDrawPoint(view.U(p[0], p[1]), view.V(p[0], 0.0)));
  const double dist = std::hypot(mid.x() - view.x, mid.y() - view.y);
  const cv::Vec3d c = kStartLine * DistanceShade(dist);
  cv::fillConvexPoly(image, pts, cv::Scalar(c[0], c[1], c[2]), cv::LINE_8, kShift);
}

void AddWall(std::vector<Item>& items, const LevelCamera& view, const Segment2& wall) {
  cv::Vec2d p0, p1;
  view.ToCamera(wall.a, p0[0], p0[1]);
  view.ToCamera(wall.b, p1[0], p1[1]);
  if (!view.ClipSegment(p0, p1)) return;
  // Fixed light from the north-east: walls facing it are brighter, so corners show.
  const Vec2 dir = wall.b - wall.a;
  const double len = dir.norm();
  if (len <= 0) return;
  const Vec2 normal(-dir.y() / len, dir.x() / len);
  const double lambert = 0.7 + 0.3 * std::abs(normal.dot(Vec2(0.6, 0.8)));
  const double clipped = cv::norm(p1 - p0);
  const int pieces = std::clamp(static_cast<int>(std::ceil(clipped / kWallPiece)), 1, 200);
  for (int i = 0; i < pieces; ++i) {
    const cv::Vec2d a = p0 + (p1 - p0) * (static_cast<double>(i) / pieces);
    const cv::Vec2d b = p0 + (p1 - p0) * (static_cast<double>(i + 1) / pieces);
    Item item;
    item.is_wall = true;
    const cv::Vec2d m = (a + b) * 0.5;
    item.dist = std::hypot(m[0], m[1]);
    item.colour = kWall * (lambert * DistanceShade(item.dist));
    const double ua = view.U(a[0], a[1]);
    const double ub = view.U(b[0], b[1]);
    item.quad[0] = ToDrawPoint(ua, view.V(a[0], kWallHeight));
    item.quad[1] = ToDrawPoint(ub, view.V(b[0], kWallHeight));
    item.quad[2] = ToDrawPoint(ub, view.V(b[0], 0.0));
    item.quad[3] = ToDrawPoint(ua, view.V(a[0], 0.0));
    items.push_back(item);
  }
}

void AddBar(std::vector<Item>& items, const LevelCamera& view, const CircleObstacle& c,
            const cv::Vec3d& colour) {
  double d = 0, l = 0;
  view.ToCamera(c.center, d, l);
  const double dist = std::hypot(d, l);
  if (dist <= c.radius + kNear || d <= kNear) return;  // inside it, touching it, or behind
  // Silhouette: the two tangent rays from the camera, as angles left of the heading.
  const double centre = std::atan2(l, d);
  const double spread = std::asin(std::min(1.0, c.radius / dist));
  const double max_angle = std::min(std::atan(view.tan_half), 1.5);
  const double left = std::min(centre + spread, max_angle);
  const double right = std::max(centre - spread, -max_angle);
  if (left <= right) return;
  Item item;
  item.is_wall = false;
  item.dist = dist;
  item.u0 = view.cx - view.f * std::tan(left);
  item.u1 = view.cx - view.f * std::tan(right);
  item.v0 = view.V(d, kPostHeight);
  item.v1 = view.V(d, 0.0);
  item.colour = colour * DistanceShade(dist);
  items.push_back(item);
}

/// A bar, shaded like a lit cylinder: brightest in the middle.
void DrawBar(cv::Mat& image, const Item& item) {
  const auto first = [](double c, int n) {
    return static_cast<int>(std::clamp(std::ceil(c - 0.5), 0.0, static_cast<double>(n)));
  };
  int c0 = first(item.u0, image.cols);
  int c1 = first(item.u1, image.cols);
  const int r0 = first(item.v0, image.rows);
  const int r1 = first(item.v1, image.rows);
  if (c0 == c1) {  // thinner than a pixel: keep it visible as one column
    const double mid = (item.u0 + item.u1) / 2;
    if (mid < 0 || mid >= image.cols) return;
    c0 = static_cast<int>(mid);
    c1 = c0 + 1;
  }
  const double width = std::max(item.u1 - item.u0, 1e-9);
  for (int c = c0; c < c1; ++c) {
    const double s = std::clamp(2.0 * (c + 0.5 - item.u0) / width - 1.0, -1.0, 1.0);
    const cv::Vec3b px = ToPixel(item.colour * (0.6 + 0.4 * std::sqrt(1.0 - s * s)));
    for (int r = r0; r < r1; ++r) image.at<cv::Vec3b>(r, c) = px;
  }
}

}  // namespace

SyntheticCamera::SyntheticCamera(const Track& track, const CameraConfig& config)
    : track_(track), config_(Validated(config)) {}

// Render keeps no state between calls: concurrent calls on one camera are safe.
// Non-finite poses, and poses farther than kMaxPoseCoord from the origin, give a
// uniform dark grey image.
void SyntheticCamera::Render(const CameraPose& pose, cv::Mat& image) const {
  image.create(config_.height, config_.width, CV_8UC3);  // no-op when it already fits
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.heading) ||
      std::abs(pose.x) > kMaxPoseCoord || std::abs(pose.y) > kMaxPoseCoord) {
    image.setTo(cv::Scalar(kInvalid[0], kInvalid[1], kInvalid[2]));
    return;
  }

  // A zoomed lens is a narrower camera (a copy only while zoomed: never for the pilot's).
  CameraConfig zoomed;
  if (pose.zoom > 1.0) {
    zoomed = config_;
    zoomed.fov_deg = ZoomedFovDeg(config_.fov_deg, pose.zoom);
  }
  const LevelCamera view =
      LevelCamera::At(pose.zoom > 1.0 ? zoomed : config_, pose.x, pose.y, pose.heading + pose.pan);

  DrawSky(image, view.cy);
  DrawFloor(image, view);
  DrawStartLine(image, view, track_.start_line(), track_.config().corridor_width);

  std::vector<Item> items;
  items.reserve(256);
  for (const Segment2& wall : track_.walls()) AddWall(items, view, wall);
  const auto same = [](const Vec2& a, const Vec2& b) { return (a - b).squaredNorm() < 1e-12; };
  for (const CircleObstacle& c : track_.round_obstacles()) {
    cv::Vec3d colour = kObstacle;
    for (const Gate& g : track_.gates()) {
      if (same(c.center, g.left_post)) {
        colour = kLeftPost;
      } else if (same(c.center, g.right_post)) {
        colour = kRightPost;
      }
    }
    AddBar(items, view, c, colour);
  }
  std::sort(items.begin(), items.end(),
            [](const Item& a, const Item& b) { return a.dist > b.dist; });

  for (const Item& item : items) {
    if (!item.is_wall) {
      DrawBar(image, item);
      continue;
    }
    const cv::Scalar fill(item.colour[0], item.colour[1], item.colour[2]);
    cv::fillConvexPoly(image, item.quad, 4, fill, cv::LINE_8, kShift);
    // A darker top edge outlines the wall against the sky and farther walls.
    cv::line(image, item.quad[0], item.quad[1], fill * 0.6, 1, cv::LINE_8, kShift);
  }
}

}  // namespace haptel::video
