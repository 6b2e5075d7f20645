/// @file The picture of a run (see run_picture.hpp).
///
/// Layout, top to bottom: a title band (two lines), the map (the track and
/// the path, to scale, with a margin), and a legend band (the speed colour bar
/// on the left, a metre scale bar on the right).
#include "haptel/record/run_picture.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace haptel::record {
namespace {

constexpr int kMarginPx = 28;      ///< around the map's content
constexpr int kTitleBandPx = 64;   ///< two title lines
constexpr int kLegendBandPx = 76;  ///< speed legend and scale bar
constexpr int kMinWidthPx = 640;   ///< room for the title and the legend
constexpr int kShift = 3;          ///< sub-pixel bits for drawing
constexpr double kSubPixel = 1 << kShift;

const cv::Scalar kWhite(255, 255, 255);
const cv::Scalar kBlack(0, 0, 0);
const cv::Scalar kCorridor(232, 232, 232);
const cv::Scalar kWall(80, 80, 80);
const cv::Scalar kCentreLine(200, 200, 200);
const cv::Scalar kObstacle(120, 120, 120);
const cv::Scalar kPathOutline(40, 40, 40);
const cv::Scalar kPassed(0, 170, 0);
const cv::Scalar kMissed(0, 0, 220);
const cv::Scalar kNotReached(160, 160, 160);
const cv::Scalar kContact(0, 0, 230);
const cv::Scalar kText(20, 20, 20);

bool Finite(double x, double y) { return std::isfinite(x) && std::isfinite(y); }

/// The world rectangle the map shows.
struct Bounds {
  double min_x = std::numeric_limits<double>::infinity();
  double min_y = std::numeric_limits<double>::infinity();
  double max_x = -std::numeric_limits<double>::infinity();
  double max_y = -std::numeric_limits<double>::infinity();

  void Add(double x, double y, double r = 0.0) {
    if (!Finite(x, y)) return;
    min_x = std::min(min_x, x - r);
    min_y = std::min(min_y, y - r);
    max_x = std::max(max_x, x + r);
    max_y = std::max(max_y, y + r);
  }
  bool empty() const { return !(min_x <= max_x && min_y <= max_y); }
};

/// The walls: the centre line offset by half the corridor on each side, with
/// mitred joins (as the track file defines them).
void Walls(const TrackConfig& track, std::vector<Vec2>& left, std::vector<Vec2>& right) {
  const auto& c = track.centerline;
  const size_t n = c.size();
  const double h = track.corridor_width / 2;
  left.resize(n);
  right.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec2 d0 = (c[i] - c[(i + n - 1) % n]).normalized();
    const Vec2 d1 = (c[(i + 1) % n] - c[i]).normalized();
    const Vec2 miter = (Vec2(-d0.y(), d0.x()) + Vec2(-d1.y(), d1.x())).normalized();
    const double len = h / miter.dot(Vec2(-d0.y(), d0.x()));
    left[i] = c[i] + miter * len;
    right[i] = c[i] - miter * len;
  }
}

/// Text the Hershey fonts can draw: each non-ASCII character becomes '?'.
std::string Ascii(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto byte = static_cast<unsigned char>(ch);
    if (byte < 0x80) {
      out += (byte < 0x20) ? ' ' : ch;
    } else if ((byte & 0xC0) != 0x80) {  // a UTF-8 lead byte; continuation bytes are dropped
      out += '?';
    }
  }
  return out;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

/// The longest 1, 2 or 5 x 10^k not above `target` (> 0).
double NiceLength(double target) {
  const double decade = std::pow(10.0, std::floor(std::log10(target)));
  for (const double step : {5.0, 2.0, 1.0}) {
    if (step * decade <= target) return step * decade;
  }
  return decade;
}

class Painter {
 public:
  explicit Painter(RunPicture& picture) : p_(picture), image_(picture.image) {}

  cv::Point At(double x, double y) const {
    const cv::Point2d q = p_.ToPixel(x, y);
    return {static_cast<int>(std::lround(q.x * kSubPixel)),
            static_cast<int>(std::lround(q.y * kSubPixel))};
  }
  cv::Point At(const Vec2& v) const { return At(v.x(), v.y()); }

  void Line(const Vec2& a, const Vec2& b, const cv::Scalar& colour, int thickness) {
    cv::line(image_, At(a), At(b), colour, thickness, cv::LINE_AA, kShift);
  }
  /// A filled circle of at least `min_px` radius, outlined in black.
  void Disc(const Vec2& c, double radius_m, int min_px, const cv::Scalar& colour) {
    const int r = std::max(min_px, static_cast<int>(std::lround(radius_m * p_.px_per_m)));
    const cv::Point at = At(c);
    cv::circle(image_, at, r << kShift, colour, cv::FILLED, cv::LINE_AA, kShift);
    cv::circle(image_, at, r << kShift, kBlack, 1, cv::LINE_AA, kShift);
  }
  /// Text with its centre at pixel `centre`.
  void TextCentred(const std::string& text, cv::Point2d centre, double scale) {
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    const cv::Point origin(static_cast<int>(std::lround(centre.x - size.width / 2.0)),
                           static_cast<int>(std::lround(centre.y + size.height / 2.0)));
    cv::putText(image_, text, origin, cv::FONT_HERSHEY_SIMPLEX, scale, kText, 1, cv::LINE_AA);
  }
  /// Text from `origin` (baseline left), shrunk to fit `max_width` px.
  void TextFitted(const std::string& text, cv::Point origin, double scale, int max_width) {
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
    if (size.width > max_width) scale *= static_cast<double>(max_width) / size.width;
    cv::putText(image_, text, origin, cv::FONT_HERSHEY_SIMPLEX, scale, kText, 1, cv::LINE_AA);
  }

 private:
  const RunPicture& p_;
  cv::Mat& image_;
};

/// 256 colours from 0 to the top speed.
cv::Mat SpeedColours() {
  cv::Mat ramp(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) ramp.at<uint8_t>(0, i) = static_cast<uint8_t>(i);
  cv::Mat colours;
  cv::applyColorMap(ramp, colours, cv::COLORMAP_PLASMA);
  return colours;
}

cv::Scalar SpeedColour(const cv::Mat& colours, double speed_mps, double max_speed_mps) {
  const double f = std::clamp(std::abs(speed_mps) / max_speed_mps, 0.0, 1.0);
  const cv::Vec3b c = colours.at<cv::Vec3b>(0, static_cast<int>(std::lround(f * 255.0)));
  return {static_cast<double>(c[0]), static_cast<double>(c[1]), static_cast<double>(c[2])};
}

/// What the map must show: the walls, the round obstacles, the path, the
/// contacts and `also_show`; a map at least 0.1 m across on each axis (a
/// path that is a single point).
struct MapExtent {
  double cx = 0.0, cy = 0.0;            ///< its centre, m
  double world_w = 0.0, world_h = 0.0;  ///< its size, m
  double max_speed = 0.0;               ///< the path's top speed, m/s (0: none)
};

MapExtent ExtentOf(const RunRecord& run, const std::optional<Track>& geometry,
                   const std::vector<Vec2>& left, const std::vector<Vec2>& right,
                   const std::vector<Vec2>& also_show) {
  Bounds bounds;
  for (const Vec2& v : left) bounds.Add(v.x(), v.y());
  for (const Vec2& v : right) bounds.Add(v.x(), v.y());
  if (geometry) {
    for (const CircleObstacle& o : geometry->round_obstacles()) {
      bounds.Add(o.center.x(), o.center.y(), o.radius);
    }
  }
  MapExtent e;
  for (const PathPoint& p : run.path) {
    bounds.Add(p.x, p.y);
    if (Finite(p.x, p.y) && std::isfinite(p.speed_mps)) {
      e.max_speed = std::max(e.max_speed, std::abs(p.speed_mps));
    }
  }
  for (const ContactPoint& c : run.contacts) bounds.Add(c.x, c.y);
  for (const Vec2& v : also_show) bounds.Add(v.x(), v.y());
  if (bounds.empty()) bounds.Add(0.0, 0.0, 0.5);
  e.cx = (bounds.min_x + bounds.max_x) / 2;
  e.cy = (bounds.min_y + bounds.max_y) / 2;
  e.world_w = std::max(bounds.max_x - bounds.min_x, 0.1);
  e.world_h = std::max(bounds.max_y - bounds.min_y, 0.1);
  return e;
}

/// The blank picture: kLongSide on the long side, the map to scale between
/// the title band and the legend band.
RunPicture LayOut(const MapExtent& e) {
  RunPicture picture;
  constexpr int kLong = RunPicture::kLongSide;
  constexpr int kBands = kTitleBandPx + kLegendBandPx + 2 * kMarginPx;
  double scale = (kLong - 2 * kMarginPx) / e.world_w;
  int width = kLong;
  int height = static_cast<int>(std::ceil(e.world_h * scale)) + kBands;
  if (height > kLong) {  // taller than wide: the height is the long side
    scale = (kLong - kBands) / e.world_h;
    height = kLong;
    width = std::max(kMinWidthPx, static_cast<int>(std::ceil(e.world_w * scale)) + 2 * kMarginPx);
  }
  picture.px_per_m = scale;
  picture.min_x = e.cx - e.world_w / 2;
  picture.max_y = e.cy + e.world_h / 2;
  picture.origin_px = {(width - e.world_w * scale) / 2, kTitleBandPx + kMarginPx};
  picture.max_speed_mps = e.max_speed > 0.0 ? e.max_speed : 1.0;
  picture.image = cv::Mat(height, width, CV_8UC3, kWhite);
  return picture;
}

/// The corridor between the walls, the centre line and the obstacles.
void DrawTrack(RunPicture& picture, Painter& paint, const TrackConfig& track,
               const std::vector<Vec2>& left, const std::vector<Vec2>& right) {
  std::vector<std::vector<cv::Point>> rings(2);
  for (size_t i = 0; i < left.size(); ++i) {
    rings[0].push_back(paint.At(left[i]));
    rings[1].push_back(paint.At(right[i]));
  }
  // One ring inside the other: the fill covers the corridor between them.
  cv::fillPoly(picture.image, rings, kCorridor, cv::LINE_AA, kShift);
  std::vector<cv::Point> centre;
  for (const Vec2& v : track.centerline) centre.push_back(paint.At(v));
  cv::polylines(picture.image, centre, true, kCentreLine, 1, cv::LINE_AA, kShift);
  cv::polylines(picture.image, rings, true, kWall, 2, cv::LINE_AA, kShift);
  for (const CircleObstacle& o : track.obstacles) paint.Disc(o.center, o.radius, 3, kObstacle);
}

/// The path, coloured by speed, on a dark outline.
void DrawPath(RunPicture& picture, Painter& paint, const RunRecord& run, const cv::Mat& colours) {
  std::vector<const PathPoint*> points;
  for (const PathPoint& p : run.path) {
    if (Finite(p.x, p.y)) points.push_back(&p);
  }
  for (size_t i = 1; i < points.size(); ++i) {
    paint.Line({points[i - 1]->x, points[i - 1]->y}, {points[i]->x, points[i]->y}, kPathOutline, 5);
  }
  for (size_t i = 1; i < points.size(); ++i) {
    const double a = std::isfinite(points[i - 1]->speed_mps) ? points[i - 1]->speed_mps : 0.0;
    const double b = std::isfinite(points[i]->speed_mps) ? points[i]->speed_mps : 0.0;
    const cv::Scalar colour =
        SpeedColour(colours, (std::abs(a) + std::abs(b)) / 2, picture.max_speed_mps);
    paint.Line({points[i - 1]->x, points[i - 1]->y}, {points[i]->x, points[i]->y}, colour, 3);
  }
  if (points.size() == 1) {
    const cv::Scalar colour = SpeedColour(colours, points[0]->speed_mps, picture.max_speed_mps);
    cv::circle(picture.image, paint.At(points[0]->x, points[0]->y), 3 << kShift, colour, cv::FILLED,
               cv::LINE_AA, kShift);
  }
}

/// The start line across the corridor, an arrow the way the lap goes, and
/// where the vehicle starts (a ring).
void DrawStart(RunPicture& picture, Painter& paint, const TrackConfig& track,
               const Track& geometry) {
  const Vec2 s = geometry.PointAt(0.0);
  const Vec2 t = geometry.TangentAt(0.0);
  const Vec2 n(-t.y(), t.x());
  const double h = track.corridor_width / 2;
  paint.Line(s - n * h, s + n * h, kBlack, 3);
  // The arrow is 40 px long whatever the scale (image rows grow downwards).
  const cv::Point tail = paint.At(s + n * (h * 0.5));
  const cv::Point head = tail + cv::Point(static_cast<int>(std::lround(t.x() * 40 * kSubPixel)),
                                          static_cast<int>(std::lround(-t.y() * 40 * kSubPixel)));
  cv::arrowedLine(picture.image, tail, head, kBlack, 2, cv::LINE_AA, kShift, 0.3);
  const Vec2 start = geometry.StartPosition();
  cv::circle(picture.image, paint.At(start), 5 << kShift, kBlack, 2, cv::LINE_AA, kShift);
  const cv::Point2d label = picture.ToPixel(s.x() + n.x() * h, s.y() + n.y() * h);
  const cv::Point2d away = picture.ToPixel(s.x() + n.x() * (h + 1.0), s.y() + n.y() * (h + 1.0));
  const cv::Point2d dir = (away - label) / std::max(cv::norm(away - label), 1e-9);
  paint.TextCentred("start", label + dir * 22.0, 0.5);
}

/// A gate's colour as the run took it: passed, missed (crossed outside), or
/// not reached. One rule for the track's and the blimp course's gates.
cv::Scalar GateColour(const std::vector<GateSplit>& splits, int gate) {
  cv::Scalar colour = kNotReached;
  for (const GateSplit& split : splits) {
    if (split.gate != gate) continue;
    if (split.passed) {
      colour = kPassed;
    } else if (split.split_s >= 0.0) {
      colour = kMissed;
    }
  }
  return colour;
}

/// The gates, as the run took them, each numbered beyond its left post.
void DrawGates(RunPicture& picture, Painter& paint, const RunRecord& run, const TrackConfig& track,
               const Track& geometry) {
  const std::vector<Gate>& gates = geometry.gates();
  for (size_t g = 0; g < gates.size(); ++g) {
    const cv::Scalar colour = GateColour(run.splits, static_cast<int>(g));
    const Gate& gate = gates[g];
    paint.Line(gate.left_post, gate.right_post, colour, 2);
    paint.Disc(gate.left_post, track.post_radius, 6, colour);
    paint.Disc(gate.right_post, track.post_radius, 6, colour);
    // The number beyond the left post, away from the gate's centre.
    const cv::Point2d post = picture.ToPixel(gate.left_post.x(), gate.left_post.y());
    const cv::Point2d centre = picture.ToPixel(gate.center.x(), gate.center.y());
    cv::Point2d out = post - centre;
    out /= std::max(cv::norm(out), 1e-9);
    const double post_px = std::max(6.0, track.post_radius * picture.px_per_m);
    paint.TextCentred(std::to_string(g + 1), post + out * (post_px + 12.0), 0.55);
  }
}

/// The contacts: red crosses outlined in black.
void DrawContacts(RunPicture& picture, Painter& paint, const RunRecord& run) {
  for (const ContactPoint& c : run.contacts) {
    if (!Finite(c.x, c.y)) continue;
    const cv::Point at = paint.At(c.x, c.y);
    constexpr int kArm = 8 << kShift;
    for (const auto& [thickness, colour] : {std::pair{6, kBlack}, std::pair{3, kContact}}) {
      cv::line(picture.image, at + cv::Point(-kArm, -kArm), at + cv::Point(kArm, kArm), colour,
               thickness, cv::LINE_AA, kShift);
      cv::line(picture.image, at + cv::Point(-kArm, kArm), at + cv::Point(kArm, -kArm), colour,
               thickness, cv::LINE_AA, kShift);
    }
  }
}

/// The title's two lines: the run and its result.
void DrawTitle(const RunPicture& picture, Painter& paint, const RunRecord& run,
               const TrackConfig& track) {
  const int width = picture.image.cols;
  std::string first = run.id > 0 ? "run " + std::to_string(run.id) + "  |  " : "";
  first += (run.config_name.empty() ? "?" : run.config_name) + "  |  track " +
           (run.track.empty() ? track.name : run.track) + "  |  " +
           (run.interface.empty() ? "?" : run.interface) + "  |  operator " +
           (run.operator_kind.empty() ? "?" : run.operator_kind);
  const std::string lap =
      std::isfinite(run.lap_time_s) ? Format("%.2f s", run.lap_time_s) : std::string("-");
  const std::string second = (run.outcome.empty() ? "?" : run.outcome) + "  |  lap " + lap +
                             "  |  gates passed " + std::to_string(run.gates_passed) + "/" +
                             std::to_string(run.gates_total) + "  |  obstacles touched " +
                             std::to_string(run.obstacles_touched);
  paint.TextFitted(Ascii(first), {16, 26}, 0.6, width - 32);
  paint.TextFitted(Ascii(second), {16, 52}, 0.6, width - 32);
}

/// The legend band: speed colours (left) and a scale bar (right) about a
/// quarter of the map's width, where there is room.
void DrawLegend(RunPicture& picture, Painter& paint, const cv::Mat& colours, double world_w) {
  const int width = picture.image.cols;
  const int top = picture.image.rows - kLegendBandPx;
  cv::line(picture.image, {0, top}, {width, top}, kCentreLine, 1);
  const int bar_x = 80;
  const int bar_w = 300;
  picture.speed_legend = cv::Rect(bar_x, top + 18, bar_w, 16);
  paint.TextFitted("speed", {16, top + 31}, 0.5, 60);
  for (int c = 0; c < bar_w; ++c) {
    const cv::Vec3b colour = colours.at<cv::Vec3b>(
        0, static_cast<int>(std::lround(255.0 * c / static_cast<double>(bar_w - 1))));
    cv::line(picture.image, {bar_x + c, top + 18}, {bar_x + c, top + 33},
             cv::Scalar(colour[0], colour[1], colour[2]), 1);
  }
  // The frame just outside the bar, so its end columns stay the end colours.
  cv::rectangle(picture.image,
                cv::Rect(bar_x - 1, top + 17, bar_w + 2, picture.speed_legend.height + 2), kBlack,
                1);
  paint.TextCentred("0 m/s", {static_cast<double>(bar_x), top + 50.0}, 0.45);
  paint.TextCentred(Format("%.2f m/s", picture.max_speed_mps),
                    {static_cast<double>(bar_x + bar_w), top + 50.0}, 0.45);

  const double scale = picture.px_per_m;
  const int room_px = width - (bar_x + bar_w + 60) - 16;
  const double target_m = std::min(world_w * 0.25, room_px / scale);
  if (target_m <= 0.0) return;
  const double length_m = NiceLength(target_m);
  const int length_px = static_cast<int>(std::lround(length_m * scale));
  const int x1 = width - 24;
  const int x0 = x1 - length_px;
  const int y = top + 28;
  cv::line(picture.image, {x0, y}, {x1, y}, kBlack, 2);
  cv::line(picture.image, {x0, y - 6}, {x0, y + 6}, kBlack, 2);
  cv::line(picture.image, {x1, y - 6}, {x1, y + 6}, kBlack, 2);
  paint.TextCentred(Format("%g m", length_m), {(x0 + x1) / 2.0, top + 50.0}, 0.45);
}

}  // namespace

RunPicture RenderRunPicture(const RunRecord& run, const TrackConfig& track,
                            const std::vector<Vec2>& also_show) {
  // A loaded track has at least 3 centre-line points; anything less is drawn
  // as no track at all (the path and contacts still are).
  std::optional<Track> geometry;
  if (track.centerline.size() >= 3) geometry.emplace(track);
  std::vector<Vec2> left;
  std::vector<Vec2> right;
  if (geometry) Walls(track, left, right);

  const MapExtent extent = ExtentOf(run, geometry, left, right, also_show);
  RunPicture picture = LayOut(extent);
  Painter paint(picture);
  const cv::Mat colours = SpeedColours();
  // Drawn in this order: the start line, the gates and the contacts on top of the path.
  if (geometry) DrawTrack(picture, paint, track, left, right);
  DrawPath(picture, paint, run, colours);
  if (geometry) {
    DrawStart(picture, paint, track, *geometry);
    DrawGates(picture, paint, run, track, *geometry);
  }
  DrawContacts(picture, paint, run);
  DrawTitle(picture, paint, run, track);
  DrawLegend(picture, paint, colours, extent.world_w);
  return picture;
}

void DrawRunPicture(const RunRecord& run, const TrackConfig& track,
                    const std::filesystem::path& png) {
  WriteRunPicture(RenderRunPicture(run, track), png);
}

RunPicture RenderBlimpRunPicture(const RunRecord& run, const BlimpCourseConfig& course) {
  // The map takes in the path and the whole course (a margin round the
  // buildings' and gates' ends and the landing circle).
  std::vector<Vec2> course_points;
  const auto around = [&](double x, double y, double r) {
    for (const auto& [dx, dy] : {std::pair{r, r}, std::pair{-r, -r}})
      course_points.emplace_back(x + dx, y + dy);
  };
  for (const BlimpBuildingSpec& b : course.buildings) {
    around(b.centre[0], b.centre[1], std::hypot(b.size[0], b.size[1]) / 2);
  }
  for (const BlimpGateSpec& g : course.gates) around(g.centre[0], g.centre[1], g.width / 2 + 3.0);
  around(course.landing.centre[0], course.landing.centre[1], course.landing.radius + 3.0);
  around(course.start.position[0], course.start.position[1], 3.0);
  TrackConfig no_track;
  no_track.name = course.name;
  RunPicture picture = RenderRunPicture(run, no_track, course_points);
  Painter paint(picture);
  const auto px = [&](double x, double y) {
    const cv::Point2d p = picture.ToPixel(x, y);
    return cv::Point(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
  };
  for (const BlimpBuildingSpec& b : course.buildings) {
    const double yaw = b.yaw_deg * M_PI / 180.0;
    const Vec2 ax(std::cos(yaw), std::sin(yaw));
    const Vec2 ay(-ax.y(), ax.x());
    const Vec2 c(b.centre[0], b.centre[1]);
    std::vector<cv::Point> corners;
    for (const auto& [sx, sy] :
         {std::pair{1, 1}, std::pair{-1, 1}, std::pair{-1, -1}, std::pair{1, -1}}) {
      const Vec2 v = c + ax * (sx * b.size[0] / 2) + ay * (sy * b.size[1] / 2);
      corners.push_back(px(v.x(), v.y()));
    }
    cv::polylines(picture.image, corners, true, kWall, 2, cv::LINE_AA);
    paint.TextCentred(Ascii(b.name) + Format(" %.0f m", b.height), px(c.x(), c.y()), 0.4);
  }
  {
    const cv::Point centre = px(course.landing.centre[0], course.landing.centre[1]);
    const int radius =
        std::max(4, static_cast<int>(std::lround(course.landing.radius * picture.px_per_m)));
    cv::circle(picture.image, centre, radius, kBlack, 2, cv::LINE_AA);
    paint.TextCentred("landing", cv::Point2d(centre) + cv::Point2d(0, radius + 12), 0.45);
    const cv::Point start = px(course.start.position[0], course.start.position[1]);
    cv::circle(picture.image, start, 6, kBlack, 2, cv::LINE_AA);
    paint.TextCentred("start", cv::Point2d(start) + cv::Point2d(0, 18), 0.45);
  }
  for (size_t g = 0; g < course.gates.size(); ++g) {
    const BlimpGateSpec& gate = course.gates[g];
    const cv::Scalar colour = GateColour(run.splits, static_cast<int>(g));
    const double heading = gate.heading_deg * M_PI / 180.0;
    const Vec2 across(-std::sin(heading), std::cos(heading));
    const Vec2 c(gate.centre[0], gate.centre[1]);
    const Vec2 a = c + across * (gate.width / 2);
    const Vec2 b = c - across * (gate.width / 2);
    cv::line(picture.image, px(a.x(), a.y()), px(b.x(), b.y()), colour, 4, cv::LINE_AA);
    paint.TextCentred(std::to_string(g + 1) + Format(" (%.0f m)", gate.centre[2]),
                      cv::Point2d(px(a.x(), a.y())) + cv::Point2d(0, -12), 0.45);
  }
  return picture;
}

void WriteRunPicture(const RunPicture& picture, const std::filesystem::path& png) {
  const auto fail = [&](const std::string& why) {
    throw std::runtime_error("run picture: " + png.string() + ": " + why);
  };

  const std::filesystem::path folder = png.parent_path();
  if (!folder.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (ec) fail("cannot create folder " + folder.string() + ": " + ec.message());
  }
  std::vector<uint8_t> bytes;
  try {
    if (!cv::imencode(".png", picture.image, bytes)) fail("cannot encode PNG");
  } catch (const cv::Exception& e) {
    fail(std::string("cannot encode PNG: ") + e.what());
  }
  // Written beside and renamed over: a reader never sees half a picture.
  std::filesystem::path partial = png;
  partial += ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot open " + partial.string() + " for writing");
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(partial, ignored);
      fail("cannot write " + partial.string());
    }
  }
  std::error_code ec;
  std::filesystem::rename(partial, png, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    fail("cannot rename " + partial.string() + ": " + ec.message());
  }
}

std::filesystem::path RunPicturePath(const std::filesystem::path& database, int64_t run_id) {
  // Named by the database too: two databases in one folder share its
  // pictures/ folder, and run 1 of one is not run 1 of the other.
  return database.parent_path() / "pictures" /
         (database.stem().string() + "-run-" + std::to_string(run_id) + ".png");
}

}  // namespace haptel::record
