#include "haptel/video/blimp_camera.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "haptel/config/blimp_course_geometry.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/geometry2d.hpp"

// How the view is drawn, back to front:
//  1. sky and ground, per pixel from a colour table indexed by the height of
//     the pixel's ray (its world z component, for a ray whose component along
//     the optical axis is 1): positive is sky, a blue gradient up from a pale
//     horizon; negative is ground, grass fading into haze with the distance
//     the ray meets the ground at. That component is linear in the pixel's
//     column and row, so the split is the true horizon whatever the attitude;
//     the table's pixel at the crossing mixes the two (no staircase);
//  2. the ground grid (5 m and 25 m lines), each line cut in pieces shaded
//     by distance, faded out where lines would crowd closer than a few pixels
//     (that reach grows with height, which is how height shows);
//  3. the start pad and the landing zone (flat polygons on the ground);
//  4. buildings and the bars of the gates' frames: boxes, sorted far to near
//     by the distance from the camera to the box, each drawn as its faces
//     that face the camera, lit by a fixed sun and hazed with distance; a
//     gate's number is drawn with its top bar.
// Camera coordinates: depth d along the optical axis F, lateral l along L
// (left), height h along U (up); a point projects to column u = cx - f*l/d and
// row v = cy - f*h/d (continuous coordinates: pixel i covers [i, i+1)).
// Every polygon and line is clipped to d >= kNear and to the sides of the view
// (widened by kMarginPx) before projection, so projected coordinates stay
// within a few pixels of the image whatever the pose.

namespace haptel::video {

namespace {

using Vec3 = Eigen::Vector3d;
using Box = BlimpCourseCamera::Box;
using GroundPolygon = BlimpCourseCamera::GroundPolygon;

constexpr double kNear = 0.05;             // near plane, m
constexpr double kMarginPx = 2.0;          // the view's sides are widened by this, px
constexpr double kMaxPoseCoord = 1e6;      // m; poses farther out are rendered as invalid
constexpr double kMinGroundHeight = 0.05;  // m; lower cameras see the ground as from this
constexpr int kShift = 4;                  // sub-pixel bits for OpenCV drawing
constexpr double kOne = 1 << kShift;
constexpr double kGroundHaze = 500.0;    // m: ground haze distance
constexpr double kAirHaze = 900.0;       // m: haze distance for boxes and ground marks
constexpr double kGridMinorM = 5.0;      // m
constexpr double kGridMajorM = 25.0;     // m
constexpr double kGridMinPx = 4.0;       // grid lines fade out where closer than this on screen
constexpr double kGridMaxReach = 400.0;  // m
constexpr int kGridPieces = 12;          // pieces per line and side, shaded by distance
constexpr int kDiscVertices = 32;
constexpr double kStartPadM = 8.0;         // m, side of the start pad
constexpr double kBuildingAmbient = 0.58;  // faces away from the sun keep this share
constexpr double kGateAmbient = 0.82;      // gates stay bright from every side
// The sky/ground colour table covers the image diagonal (at most 4096x4096).
constexpr int kMaxTable = 6000;
constexpr int kMaxClip = GroundPolygon::kMaxVertices + 8;

// Palette (BGR).
const cv::Vec3d kSkyZenith(215, 150, 90);
const cv::Vec3d kSkyHorizon(245, 225, 200);
const cv::Vec3d kGrass(70, 128, 88);
const cv::Vec3d kGroundFar(165, 178, 170);
const cv::Vec3d kAirHazeColour(220, 210, 200);
const cv::Vec3d kGridMinor(100, 158, 118);
const cv::Vec3d kGridMajor(135, 190, 150);
const cv::Vec3d kGate(0, 110, 255);
const cv::Vec3d kPad(150, 150, 150);
const cv::Vec3d kPadArrow(240, 240, 240);
const cv::Vec3d kLandingRim(240, 240, 240);
const cv::Vec3d kLanding(40, 200, 235);
const std::array<cv::Vec3d, 4> kBuildings = {cv::Vec3d(170, 172, 176), cv::Vec3d(90, 105, 155),
                                             cv::Vec3d(150, 135, 120), cv::Vec3d(120, 150, 180)};
const cv::Vec3b kInvalid(60, 60, 60);

// Box faces: corner indices (cyclic) and which normal (index into +a,-a,+b,-b,+z,-z).
constexpr int kFaces[6][4] = {{1, 3, 7, 5}, {0, 2, 6, 4}, {2, 3, 7, 6},
                              {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 1, 3, 2}};

cv::Vec3b ToPixel(const cv::Vec3d& c) {
  return {cv::saturate_cast<uint8_t>(c[0]), cv::saturate_cast<uint8_t>(c[1]),
          cv::saturate_cast<uint8_t>(c[2])};
}
cv::Scalar ToScalar(const cv::Vec3d& c) { return {c[0], c[1], c[2]}; }
cv::Vec3d Mix(const cv::Vec3d& a, const cv::Vec3d& b, double t) { return a * (1 - t) + b * t; }

/// A colour seen through `dist` metres of air.
cv::Vec3d Hazed(const cv::Vec3d& c, double dist) {
  return Mix(c, kAirHazeColour, 1.0 - std::exp(-dist / kAirHaze));
}

/// The ground's colour `dist` metres away (horizontally).
cv::Vec3d GroundAt(double dist) {
  return Mix(kGrass, kGroundFar, 1.0 - std::exp(-dist / kGroundHaze));
}

/// Lambert shading under a fixed sun, high in the east-north-east, over
/// `ambient` (the share of the colour a face turned away from the sun keeps).
double Shade(const Vec3& normal, double ambient) {
  static const Vec3 sun = Vec3(0.5, 0.3, 0.8).normalized();
  return ambient + (1.0 - ambient) * std::max(0.0, normal.dot(sun));
}

/// One frame's projection.
struct Frame {
  Vec3 c, F, L, U;   // camera position and axes (world)
  double f, cx, cy;  // focal length (px) and principal point
  double tu, tv;     // tangents of the half field of view, widened by kMarginPx
  double ground_h;   // camera height for ground shading, >= kMinGroundHeight

  Vec3 ToCamera(const Vec3& p) const {
    const Vec3 r = p - c;
    return {r.dot(F), r.dot(L), r.dot(U)};
  }
  /// Signed distance-like value of camera point q to clip plane i (>= 0 inside).
  double Plane(int i, const Vec3& q) const {
    switch (i) {
      case 0:
        return q[0] - kNear;
      case 1:
        return tu * q[0] - q[1];
      case 2:
        return tu * q[0] + q[1];
      case 3:
        return tv * q[0] - q[2];
      default:
        return tv * q[0] + q[2];
    }
  }
  /// Drawing coordinates (pixel centres, kShift fractional bits) of a clipped camera point.
  cv::Point Project(const Vec3& q) const {
    const double u = cx - f * q[1] / q[0];
    const double v = cy - f * q[2] / q[0];
    return {static_cast<int>(std::lround((u - 0.5) * kOne)),
            static_cast<int>(std::lround((v - 0.5) * kOne))};
  }
};

/// Clips a convex polygon (camera coordinates) to the view (Sutherland-Hodgman).
/// `a` holds the n input points and has room for kMaxClip; `b` is scratch of
/// the same size. Returns the result's size; the result is in `*out`.
int ClipPolygon(const Frame& frame, Vec3* a, Vec3* b, int n, Vec3** out) {
  Vec3* in = a;
  Vec3* res = b;
  for (int plane = 0; plane < 5 && n > 0; ++plane) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3& p = in[i];
      const Vec3& q = in[(i + 1) % n];
      const double gp = frame.Plane(plane, p);
      const double gq = frame.Plane(plane, q);
      if (gp >= 0) res[m++] = p;
      if ((gp >= 0) != (gq >= 0) && m < kMaxClip) res[m++] = p + (q - p) * (gp / (gp - gq));
      if (m >= kMaxClip) break;
    }
    n = m;
    std::swap(in, res);
  }
  *out = in;
  return n;
}

/// Clips segment p-q (camera coordinates) to the view (Liang-Barsky).
bool ClipSegment(const Frame& frame, Vec3& p, Vec3& q) {
  double t0 = 0.0;
  double t1 = 1.0;
  for (int plane = 0; plane < 5; ++plane) {
    const double gp = frame.Plane(plane, p);
    const double gq = frame.Plane(plane, q);
    if (gp < 0 && gq < 0) return false;
    if (gp < 0) t0 = std::max(t0, gp / (gp - gq));
    if (gq < 0) t1 = std::min(t1, gp / (gp - gq));
    if (t0 >= t1) return false;
  }
  const Vec3 d = q - p;
  q = p + d * t1;
  p = p + d * t0;
  return true;
}

/// Fills the world polygon `world` (n <= GroundPolygon::kMaxVertices points,
/// convex, planar), clipped to the view; with `outline`, draws its edges too.
void FillPolygon(cv::Mat& image, const Frame& frame, const Vec3* world, int n,
                 const cv::Vec3d& colour, const cv::Vec3d* outline = nullptr) {
  std::array<Vec3, kMaxClip> a;
  std::array<Vec3, kMaxClip> b;
  for (int i = 0; i < n; ++i) a[i] = frame.ToCamera(world[i]);
  Vec3* clipped = nullptr;
  const int m = ClipPolygon(frame, a.data(), b.data(), n, &clipped);
  if (m < 3) return;
  std::array<cv::Point, kMaxClip> pts;
  for (int i = 0; i < m; ++i) pts[i] = frame.Project(clipped[i]);
  cv::fillConvexPoly(image, pts.data(), m, ToScalar(colour), cv::LINE_8, kShift);
  if (outline != nullptr) {  // cv::line, unlike cv::polylines, allocates nothing
    for (int i = 0; i < m; ++i) {
      cv::line(image, pts[i], pts[(i + 1) % m], ToScalar(*outline), 1, cv::LINE_8, kShift);
    }
  }
}

// ---- Sky and ground --------------------------------------------------------

/// Colour of a ray whose world z component is k (optical-axis component 1);
/// `step` is how much k changes from one pixel to the next, for the horizon's
/// anti-aliasing.
cv::Vec3d SkyGround(double k, double step, double ground_h) {
  const double sky_t = std::clamp(std::atan(std::max(k, 0.0)) / 1.2, 0.0, 1.0);
  const cv::Vec3d sky = Mix(kSkyHorizon, kSkyZenith, std::sqrt(sky_t));
  const cv::Vec3d ground = GroundAt(ground_h / std::max(-k, 1e-12));
  const double sky_share = step > 0 ? std::clamp(k / step + 0.5, 0.0, 1.0) : (k > 0 ? 1.0 : 0.0);
  return Mix(ground, sky, sky_share);
}

void DrawSkyAndGround(cv::Mat& image, const Frame& frame) {
  // k(u, v) = F.z + L.z*(cx - u - 0.5)/f + U.z*(cy - v - 0.5)/f = k0 + ku*u + kv*v.
  const double ku = -frame.L.z() / frame.f;
  const double kv = -frame.U.z() / frame.f;
  const double k0 = frame.F.z() + frame.L.z() * (frame.cx - 0.5) / frame.f +
                    frame.U.z() * (frame.cy - 0.5) / frame.f;
  const double step = std::hypot(ku, kv);  // k per pixel, steepest
  const int cols = image.cols;
  if (step < 1e-12) {  // looking straight up or down
    image.setTo(ToScalar(SkyGround(k0, 0.0, frame.ground_h)));
    return;
  }
  const double last_u = cols - 1;
  const double last_v = image.rows - 1;
  const double corners[4] = {k0, k0 + ku * last_u, k0 + kv * last_v,
                             k0 + ku * last_u + kv * last_v};
  const double kmin = *std::min_element(corners, corners + 4);
  const double kmax = *std::max_element(corners, corners + 4);
  const int size = std::clamp(static_cast<int>((kmax - kmin) / step) + 2, 1, kMaxTable);
  std::array<cv::Vec3b, kMaxTable> table;
  for (int i = 0; i < size; ++i)
    table[i] = ToPixel(SkyGround(kmin + i * step, step, frame.ground_h));
  // Table index of a pixel, rounded: (k - kmin)/step + 0.5.
  const double iu = ku / step;
  const double iv = kv / step;
  const double i0 = (k0 - kmin) / step + 0.5;
  const auto index = [size](double t) {
    return std::clamp(static_cast<int>(t), 0, size - 1);  // t >= -rounding error
  };
  for (int r = 0; r < image.rows; ++r) {
    cv::Vec3b* row = image.ptr<cv::Vec3b>(r);
    const double t = i0 + iv * r;
    if (std::abs(iu) * cols < 0.5) {  // the same colour along the whole row
      std::fill(row, row + cols, table[index(t + iu * cols * 0.5)]);
      continue;
    }
    // Runs of equal index: at most one change per pixel (|iu| <= 1).
    int u = 0;
    while (u < cols) {
      const int i = index(t + iu * u);
      // First column past u whose index differs.
      const double edge = iu > 0 ? (i + 1 - t) / iu : (i - t) / iu;
      int end = std::clamp(static_cast<int>(std::ceil(edge)), u + 1, cols);
      if (i == 0 || i == size - 1) end = u + 1;  // clamped ends: step pixel by pixel
      std::fill(row + u, row + end, table[i]);
      u = end;
    }
  }
}

// ---- Ground marks ----------------------------------------------------------

void DrawGrid(cv::Mat& image, const Frame& frame, double spacing, const cv::Vec3d& line_colour,
              double strength, int skip_every) {
  // Lines at distance D perpendicular to the view are about f*h*spacing/D^2
  // pixels apart: the grid reaches where that is kGridMinPx.
  const double reach =
      std::min(std::sqrt(frame.f * frame.ground_h * spacing / kGridMinPx), kGridMaxReach);
  if (reach <= spacing) return;
  std::array<cv::Scalar, kGridPieces> colours;
  for (int j = 0; j < kGridPieces; ++j) {
    const double mid = reach * (j + 0.5) / kGridPieces;
    const double alpha = strength * (1.0 - (j + 0.5) / kGridPieces);
    colours[j] = ToScalar(Mix(GroundAt(mid), Hazed(line_colour, mid), alpha));
  }
  for (int axis = 0; axis < 2; ++axis) {
    // Lines of constant world coordinate `axis`, running along the other one.
    const double p = frame.c[axis];
    const double q = frame.c[1 - axis];
    const auto point = [axis](double along_p, double along_q) {
      Vec3 w(0.0, 0.0, 0.0);
      w[axis] = along_p;
      w[1 - axis] = along_q;
      return w;
    };
    const long long first = static_cast<long long>(std::ceil((p - reach) / spacing));
    const long long last = static_cast<long long>(std::floor((p + reach) / spacing));
    for (long long k = first; k <= last; ++k) {
      if (skip_every > 0 && k % skip_every == 0) continue;
      const double at = static_cast<double>(k) * spacing;
      const double off = at - p;
      if (std::abs(off) >= reach) continue;
      const double half = std::sqrt(reach * reach - off * off);
      Vec3 a = frame.ToCamera(point(at, q - half));
      Vec3 b = frame.ToCamera(point(at, q + half));
      if (!ClipSegment(frame, a, b)) continue;  // none of this line is in view
      // Pieces between the distances reach*j/kGridPieces, on both sides of the
      // point of the line nearest the camera.
      double prev = 0.0;
      for (int j = 0; j < kGridPieces; ++j) {
        const double radius = reach * (j + 1) / kGridPieces;
        if (radius <= std::abs(off)) continue;
        const double next = std::sqrt(radius * radius - off * off);
        for (const double side : {-1.0, 1.0}) {
          Vec3 s0 = frame.ToCamera(point(at, q + side * prev));
          Vec3 s1 = frame.ToCamera(point(at, q + side * next));
          if (!ClipSegment(frame, s0, s1)) continue;
          cv::line(image, frame.Project(s0), frame.Project(s1), colours[j], 1, cv::LINE_AA, kShift);
        }
        prev = next;
      }
    }
  }
}

// ---- Boxes -----------------------------------------------------------------

Box MakeBox(const Vec3& centre, double yaw, const Vec3& half, const cv::Vec3d& side,
            const cv::Vec3d& top, double ambient) {
  Box box;
  box.centre = centre;
  box.axis_a = Vec3(std::cos(yaw), std::sin(yaw), 0.0);
  box.axis_b = Vec3(-std::sin(yaw), std::cos(yaw), 0.0);
  box.half = half;
  for (int i = 0; i < 8; ++i) {
    const double sa = (i & 1) ? 1.0 : -1.0;
    const double sb = (i & 2) ? 1.0 : -1.0;
    const double sz = (i & 4) ? 1.0 : -1.0;
    box.corners[i] = centre + box.axis_a * (sa * half[0]) + box.axis_b * (sb * half[1]) +
                     Vec3(0.0, 0.0, sz * half[2]);
  }
  const Vec3 normals[6] = {box.axis_a,  -box.axis_a,   box.axis_b,
                           -box.axis_b, Vec3::UnitZ(), -Vec3::UnitZ()};
  for (int face = 0; face < 6; ++face) {
    box.face_colour[face] = (face >= 4 ? top : side) * Shade(normals[face], ambient);
  }
  return box;
}

/// Distance from the camera to the nearest point of the box.
double DistanceTo(const Box& box, const Vec3& c) {
  const Vec3 r = c - box.centre;
  const Vec3 local(r.dot(box.axis_a), r.dot(box.axis_b), r.z());
  const Vec3 outside = (local.cwiseAbs() - box.half).cwiseMax(0.0);
  return outside.norm();
}

// Gate numbers are drawn once, at kLabelTextPx, into a mask; each frame
// scales the mask onto the picture (nearest pixel).
constexpr int kLabelFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kLabelScale = 2.0;
constexpr int kLabelThickness = 4;
constexpr double kLabelTextPx = 22.0 * kLabelScale;  // the font's digits: ~22 px at scale 1
const cv::Vec3d kLabelOutline(30, 30, 30);
const cv::Vec3d kLabelFill(255, 255, 255);

cv::Mat LabelMask(int number) {
  const std::string text = std::to_string(number);
  int baseline = 0;
  const cv::Size size =
      cv::getTextSize(text, kLabelFont, kLabelScale, kLabelThickness + 4, &baseline);
  const int pad = kLabelThickness + 2;
  cv::Mat outline = cv::Mat::zeros(size.height + 2 * pad, size.width + 2 * pad, CV_8UC1);
  cv::Mat fill = cv::Mat::zeros(outline.size(), CV_8UC1);
  const cv::Point origin(pad, pad + size.height);
  cv::putText(outline, text, origin, kLabelFont, kLabelScale, cv::Scalar(255), kLabelThickness + 4,
              cv::LINE_AA);
  cv::putText(fill, text, origin, kLabelFont, kLabelScale, cv::Scalar(255), kLabelThickness,
              cv::LINE_AA);
  cv::Mat mask;
  cv::merge(std::vector<cv::Mat>{outline, fill}, mask);
  return mask;
}

void DrawLabel(cv::Mat& image, const Frame& frame, const Box& box) {
  const Vec3 q = frame.ToCamera(box.label_centre);
  if (q[0] < kNear || box.label_mask.empty()) return;
  const double px = frame.f * box.label_height / q[0];  // text height, px
  if (px < 7.0) return;
  const double s = std::min(px / kLabelTextPx, 4.0);  // picture pixels per mask pixel
  const double u = frame.cx - frame.f * q[1] / q[0];
  const double v = frame.cy - frame.f * q[2] / q[0];
  const cv::Mat& mask = box.label_mask;
  const double left = u - mask.cols * s / 2;
  const double top = v - mask.rows * s / 2;
  const auto first = [](double c, int n) {
    return static_cast<int>(std::clamp(std::ceil(c - 0.5), 0.0, static_cast<double>(n)));
  };
  const int c0 = first(left, image.cols);
  const int c1 = first(left + mask.cols * s, image.cols);
  const int r0 = first(top, image.rows);
  const int r1 = first(top + mask.rows * s, image.rows);
  for (int r = r0; r < r1; ++r) {
    const int mr = std::min(static_cast<int>((r + 0.5 - top) / s), mask.rows - 1);
    const cv::Vec2b* src = mask.ptr<cv::Vec2b>(mr);
    cv::Vec3b* dst = image.ptr<cv::Vec3b>(r);
    for (int c = c0; c < c1; ++c) {
      const cv::Vec2b m = src[std::min(static_cast<int>((c + 0.5 - left) / s), mask.cols - 1)];
      if (m[0] == 0) continue;
      const cv::Vec3d under(dst[c][0], dst[c][1], dst[c][2]);
      const cv::Vec3d outlined = Mix(under, kLabelOutline, m[0] / 255.0);
      dst[c] = ToPixel(Mix(outlined, kLabelFill, m[1] / 255.0));
    }
  }
}

void DrawBox(cv::Mat& image, const Frame& frame, const Box& box, double dist) {
  const Vec3 normals[6] = {box.axis_a,  -box.axis_a,   box.axis_b,
                           -box.axis_b, Vec3::UnitZ(), -Vec3::UnitZ()};
  for (int face = 0; face < 6; ++face) {
    const Vec3& on_face = box.corners[kFaces[face][0]];
    if ((frame.c - on_face).dot(normals[face]) <= 0) continue;  // faces away
    const Vec3 quad[4] = {box.corners[kFaces[face][0]], box.corners[kFaces[face][1]],
                          box.corners[kFaces[face][2]], box.corners[kFaces[face][3]]};
    const cv::Vec3d colour = Hazed(box.face_colour[face], dist);
    const cv::Vec3d edge = colour * 0.75;
    FillPolygon(image, frame, quad, 4, colour, &edge);
  }
  if (box.label > 0) DrawLabel(image, frame, box);
}

GroundPolygon Disc(const Vec3& centre, double radius, const cv::Vec3d& colour) {
  GroundPolygon disc;
  disc.count = kDiscVertices;
  disc.colour = colour;
  disc.centre = centre;
  for (int i = 0; i < kDiscVertices; ++i) {
    const double a = 2.0 * std::numbers::pi * i / kDiscVertices;
    disc.vertices[i] = centre + Vec3(radius * std::cos(a), radius * std::sin(a), 0.0);
  }
  return disc;
}

GroundPolygon Polygon(std::initializer_list<Vec3> points, const cv::Vec3d& colour) {
  GroundPolygon poly;
  poly.colour = colour;
  poly.centre = Vec3::Zero();
  for (const Vec3& p : points) {
    poly.vertices[poly.count++] = p;
    poly.centre += p;
  }
  poly.centre /= poly.count;
  return poly;
}

}  // namespace

BlimpCourseCamera::BlimpCourseCamera(const BlimpCourseConfig& course, const CameraConfig& config)
    : config_(Validated(config)) {
  for (char ch : config_.name.substr(0, 4)) {
    overlay_name_ += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  }
  // Start pad: a square with an arrow along the start heading.
  {
    const Vec3 c(course.start.position[0], course.start.position[1], 0.0);
    const double yaw = Radians(course.start.heading_deg);
    const Vec3 a(std::cos(yaw), std::sin(yaw), 0.0);
    const Vec3 b(-a.y(), a.x(), 0.0);
    const double h = kStartPadM / 2;
    ground_.push_back(Polygon(
        {c - a * h - b * h, c + a * h - b * h, c + a * h + b * h, c - a * h + b * h}, kPad));
    ground_.push_back(Polygon(
        {c + a * (0.4 * h), c + a * (0.8 * h), c + a * (0.4 * h) + b * (0.4 * h)}, kPadArrow));
    ground_.push_back(Polygon(
        {c + a * (0.4 * h) - b * (0.4 * h), c + a * (0.8 * h), c + a * (0.4 * h)}, kPadArrow));
    ground_.push_back(
        Polygon({c - a * (0.7 * h) - b * (0.12 * h), c + a * (0.4 * h) - b * (0.12 * h),
                 c + a * (0.4 * h) + b * (0.12 * h), c - a * (0.7 * h) + b * (0.12 * h)},
                kPadArrow));
  }
  // Landing zone: a white rim around a yellow disc.
  {
    const Vec3 c(course.landing.centre[0], course.landing.centre[1], 0.0);
    ground_.push_back(Disc(c, course.landing.radius, kLandingRim));
    ground_.push_back(Disc(c, course.landing.radius * 0.85, kLanding));
  }
  // Buildings.
  for (size_t i = 0; i < course.buildings.size(); ++i) {
    const auto& bld = course.buildings[i];
    const cv::Vec3d colour = kBuildings[i % kBuildings.size()];
    boxes_.push_back(MakeBox(Vec3(bld.centre[0], bld.centre[1], bld.height / 2),
                             Radians(bld.yaw_deg),
                             Vec3(bld.size[0] / 2, bld.size[1] / 2, bld.height / 2), colour,
                             colour * 0.8, kBuildingAmbient));
  }
  // Gates: four bars around each opening, the posts spanning the corners.
  for (size_t i = 0; i < course.gates.size(); ++i) {
    const auto& gate = course.gates[i];
    const BlimpGateFrame frame = MakeGateFrame(gate);
    const Vec3 c = frame.centre, left = frame.left;
    const double yaw = Radians(gate.heading_deg);
    const double w = frame.half_width;
    const double h = frame.half_height;
    const double t = std::clamp(0.08 * std::min(gate.width, gate.height), 0.15, 1.0);  // bar
    const Vec3 post(t / 2, t / 2, h + t);
    const Vec3 bar(t / 2, w, t / 2);
    boxes_.push_back(MakeBox(c + left * (w + t / 2), yaw, post, kGate, kGate, kGateAmbient));
    boxes_.push_back(MakeBox(c - left * (w + t / 2), yaw, post, kGate, kGate, kGateAmbient));
    boxes_.push_back(MakeBox(c - Vec3(0, 0, h + t / 2), yaw, bar, kGate, kGate, kGateAmbient));
    Box top = MakeBox(c + Vec3(0, 0, h + t / 2), yaw, bar, kGate, kGate, kGateAmbient);
    top.label = static_cast<int>(i) + 1;
    top.label_height = std::clamp(0.3 * gate.height, 0.5, 4.0);
    top.label_centre = c + Vec3(0, 0, h + t + 0.8 * top.label_height);
    top.label_mask = LabelMask(top.label);
    boxes_.push_back(top);
  }
}

namespace {
/// A zoom lens's picture says its zoom, bottom left: "SURV 4.0x". Digits
/// drawn small, in the corner a gate's number is never read from.
void DrawZoomLine(cv::Mat& image, const std::string& name, double zoom) {
  char text[48];
  std::snprintf(text, sizeof text, "%s %.1fx", name.c_str(), std::max(1.0, zoom));
  const cv::Point at(8, image.rows - 10);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(20, 20, 20), 4,
              cv::LINE_AA);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(80, 255, 255), 1,
              cv::LINE_AA);
}
}  // namespace

void BlimpCourseCamera::Render(const CameraPose& pose, cv::Mat& image) const {
  image.create(config_.height, config_.width, CV_8UC3);  // no-op when it already fits
  const double values[] = {pose.x,     pose.y,    pose.z,   pose.heading,
                           pose.pitch, pose.roll, pose.pan, pose.tilt};
  const bool finite =
      std::all_of(std::begin(values), std::end(values), [](double v) { return std::isfinite(v); });
  if (!finite || std::abs(pose.x) > kMaxPoseCoord || std::abs(pose.y) > kMaxPoseCoord ||
      std::abs(pose.z) > kMaxPoseCoord) {
    image.setTo(ToScalar(cv::Vec3d(kInvalid[0], kInvalid[1], kInvalid[2])));
    return;
  }

  // Body: yaw about z, pitch nose up (about -y), roll right side down (about
  // +x); then the head: pan about the body's z, tilt up (about -y).
  using Eigen::AngleAxisd;
  const Eigen::Matrix3d r =
      (AngleAxisd(pose.heading, Vec3::UnitZ()) * AngleAxisd(-pose.pitch, Vec3::UnitY()) *
       AngleAxisd(pose.roll, Vec3::UnitX()) * AngleAxisd(pose.pan, Vec3::UnitZ()) *
       AngleAxisd(-pose.tilt, Vec3::UnitY()))
          .toRotationMatrix();
  Frame frame{};
  frame.c = Vec3(pose.x, pose.y, pose.z);
  frame.F = r.col(0);
  frame.L = r.col(1);
  frame.U = r.col(2);
  const double fov_deg = ZoomedFovDeg(config_.fov_deg, pose.zoom);
  frame.f = (config_.width / 2.0) / std::tan(Radians(fov_deg) / 2.0);
  frame.cx = config_.width / 2.0;
  frame.cy = config_.height / 2.0;
  frame.tu = (frame.cx + kMarginPx) / frame.f;
  frame.tv = (frame.cy + kMarginPx) / frame.f;
  frame.ground_h = std::max(pose.z, kMinGroundHeight);

  DrawSkyAndGround(image, frame);
  if (pose.z > 0.0) {  // from below, the ground hides its marks
    DrawGrid(image, frame, kGridMinorM, kGridMinor, 0.8,
             static_cast<int>(kGridMajorM / kGridMinorM));
    DrawGrid(image, frame, kGridMajorM, kGridMajor, 1.0, 0);
    for (const GroundPolygon& poly : ground_) {
      const double dist = (poly.centre - frame.c).norm();
      FillPolygon(image, frame, poly.vertices.data(), poly.count, Hazed(poly.colour, dist));
    }
  }

  // Boxes far to near; a fixed array for the order unless the course is large.
  struct Order {
    double dist;
    int index;
  };
  constexpr size_t kStackBoxes = 256;
  std::array<Order, kStackBoxes> stack_order;
  std::vector<Order> heap_order;
  std::span<Order> order(stack_order.data(), std::min(boxes_.size(), kStackBoxes));
  if (boxes_.size() > kStackBoxes) {
    heap_order.resize(boxes_.size());
    order = heap_order;
  }
  for (size_t i = 0; i < boxes_.size(); ++i) {
    order[i] = {DistanceTo(boxes_[i], frame.c), static_cast<int>(i)};
  }
  std::sort(order.begin(), order.end(),
            [](const Order& a, const Order& b) { return a.dist > b.dist; });
  for (const Order& o : order) DrawBox(image, frame, boxes_[o.index], o.dist);
  if (config_.zoom_max > 1.0) DrawZoomLine(image, overlay_name_, pose.zoom);
}

std::unique_ptr<CameraSource> MakeBlimpCameraSource(const CameraConfig& config,
                                                    const BlimpCourseConfig& course,
                                                    const std::string& config_file) {
  if (config.source == CameraSourceKind::kSynthetic) {
    return std::make_unique<BlimpCourseSource>(course, config);
  }
  // Devices and files: the same sources, checks and errors as any vehicle's.
  return MakeCameraSource(config, nullptr, config_file);
}

}  // namespace haptel::video
