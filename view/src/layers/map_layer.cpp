#include "map_layer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace haptel::view::layers {
namespace {

/// The map's scale and offset for `map` in a `side`-pixel square: the
/// track's walls and posts fit, to scale, north up.
void FitMap(const TrackMap& map, int side, double& scale, double& ox, double& oy) {
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  const auto grow = [&](double x, double y, double r) {
    x0 = std::min(x0, x - r);
    y0 = std::min(y0, y - r);
    x1 = std::max(x1, x + r);
    y1 = std::max(y1, y + r);
  };
  for (const TrackMap::Line& l : map.walls) {
    grow(l.ax, l.ay, 0);
    grow(l.bx, l.by, 0);
  }
  for (const TrackMap::Post& p : map.posts) grow(p.x, p.y, p.radius);
  for (const TrackMap::Line& l : map.gates) {
    grow(l.ax, l.ay, 0);
    grow(l.bx, l.by, 0);
  }
  if (!map.walls.empty() || !map.posts.empty()) {  // a map with nothing but a start line is no map
    grow(map.start.ax, map.start.ay, 0);
    grow(map.start.bx, map.start.by, 0);
  }
  if (x1 < x0) {  // nothing to fit: a metre around the origin
    x0 = y0 = -0.5;
    x1 = y1 = 0.5;
  }
  const double margin = 0.06 * side;
  scale = (side - 2 * margin) / std::max({x1 - x0, y1 - y0, 1e-3});
  ox = side / 2.0 - scale * (x0 + x1) / 2;
  oy = side / 2.0 + scale * (y0 + y1) / 2;
}

}  // namespace

MapLayer::MapLayer(const TexturedQuads& quads) : quads_(quads), texture_(MakeTexture()) {}

MapLayer::~MapLayer() { glDeleteTextures(1, &texture_); }

cv::Point MapLayer::PanelPoint(double x, double y) const {
  return Fixed(ox_ + scale_ * x - 0.5, oy_ - scale_ * y - 0.5);
}

void MapLayer::Draw(const ViewModel& model, const Frame& frame) {
  drawn_ = false;
  const Prediction& pr = model.prediction;
  if (!pr.shown || !model.map) return;
  const int side = static_cast<int>(0.36 * frame.height);
  const int line_h = static_cast<int>(18 * frame.height / 576.0);
  // A flying vehicle's heights take a third line under the legend.
  const int lines = pr.heights ? 3 : 2;
  const cv::Rect panel(frame.width - side - 8, 8, side, side + lines * line_h + 6);
  if (track_of_ != model.map.get() || track_.size() != panel.size()) {
    track_of_ = model.map.get();
    RasteriseTrack(*model.map, panel.size(), side, frame);
  }
  track_.copyTo(map_);
  RasterisePoses(pr, side, frame);
  quads_.BeginOverWorld();
  glBindTexture(GL_TEXTURE_2D, texture_);
  UploadBgra(map_);
  quads_.DrawPixels(panel, frame.width, frame.height);
  panel_ = panel;
  drawn_ = true;
}

void MapLayer::RasteriseTrack(const TrackMap& map, const cv::Size& panel, int side,
                              const Frame& frame) {
  track_ = cv::Mat(panel, CV_8UC4, Bgra(0, 0, 0, 170));
  FitMap(map, side, scale_, ox_, oy_);
  const auto line = [&](const TrackMap::Line& l, const cv::Scalar& colour) {
    cv::line(track_, PanelPoint(l.ax, l.ay), PanelPoint(l.bx, l.by), colour, 1, cv::LINE_AA,
             kShift);
  };
  for (const TrackMap::Line& l : map.walls) line(l, Bgra(200, 200, 200));
  line(map.start, Bgra(120, 120, 120));
  for (const TrackMap::Line& l : map.gates) line(l, Bgra(0, 200, 230));
  for (const TrackMap::Post& p : map.posts) {
    const bool landing = p.kind == TrackMap::PostKind::kLanding;
    const cv::Scalar c = p.kind == TrackMap::PostKind::kLeft    ? Bgra(40, 40, 225)
                         : p.kind == TrackMap::PostKind::kRight ? Bgra(50, 200, 40)
                         : landing                              ? Bgra(120, 220, 120)
                                                                : Bgra(0, 140, 255);
    cv::circle(track_, PanelPoint(p.x, p.y),
               static_cast<int>(std::max(2.0, p.radius * scale_) * kOne), c,
               landing ? 1 : cv::FILLED, cv::LINE_AA, kShift);
  }
  const double text = 0.42 * frame.height / 576.0;
  for (const TrackMap::Label& l : map.labels) {
    // Right of the place, or left of it where the panel ends.
    int baseline = 0;
    const cv::Size size =
        cv::getTextSize(l.text, cv::FONT_HERSHEY_SIMPLEX, 0.85 * text, 1, &baseline);
    const int x = static_cast<int>(ox_ + scale_ * l.x);
    const cv::Point at(x + 4 + size.width < side ? x + 4 : std::max(0, x - 4 - size.width),
                       static_cast<int>(oy_ - scale_ * l.y) - 4);
    cv::putText(track_, l.text, at, cv::FONT_HERSHEY_SIMPLEX, 0.85 * text, Bgra(0, 200, 230), 1,
                cv::LINE_AA);
  }
  const int line_h = static_cast<int>(18 * frame.height / 576.0);
  cv::circle(track_, cv::Point(10, side + line_h - 4), 4, kReported, 2, cv::LINE_AA);
  cv::putText(track_, "as last reported", cv::Point(20, side + line_h), cv::FONT_HERSHEY_SIMPLEX,
              text, kReported, 1, cv::LINE_AA);
  cv::circle(track_, cv::Point(10, side + 2 * line_h - 4), 5, kGhostLine, cv::FILLED, cv::LINE_AA);
}

void MapLayer::RasterisePoses(const Prediction& pr, int side, const Frame& frame) {
  const int line_h = static_cast<int>(18 * frame.height / 576.0);
  const double body = std::max(4.0, pr.body_radius * scale_);
  // A pose: its body to scale (at least a few pixels), a tick to the rim
  // for its heading; the path ahead runs on beyond the predicted one.
  const auto pose = [&](const MapPose& p, const cv::Scalar& c, const cv::Scalar& tick,
                        bool filled) {
    const cv::Point centre = PanelPoint(p.x, p.y);
    const double reach = body / scale_;
    const cv::Point nose =
        PanelPoint(p.x + reach * std::cos(p.heading), p.y + reach * std::sin(p.heading));
    cv::circle(map_, centre, static_cast<int>(body * kOne), c, filled ? cv::FILLED : 2, cv::LINE_AA,
               kShift);
    cv::line(map_, centre, nose, tick, 2, cv::LINE_AA, kShift);
  };
  const int n = std::clamp(pr.map_path_count, 0, Prediction::kPathMax);
  for (int i = 1; i < n; ++i) {
    const MapPose& a = pr.map_path[static_cast<size_t>(i - 1)];
    const MapPose& b = pr.map_path[static_cast<size_t>(i)];
    cv::line(map_, PanelPoint(a.x, a.y), PanelPoint(b.x, b.y), kGhostLine, 2, cv::LINE_AA, kShift);
  }
  pose(pr.reported, kReported, kReported, false);
  pose(pr.predicted, kGhostLine, Bgra(40, 0, 40), true);
  char label[64];
  std::snprintf(label, sizeof label, "now, +%.0f ms; path: 1 s", pr.one_way_delay_s * 1e3);
  cv::putText(map_, label, cv::Point(20, side + 2 * line_h), cv::FONT_HERSHEY_SIMPLEX,
              0.42 * frame.height / 576.0, kGhostLine, 1, cv::LINE_AA);
  if (pr.heights && n > 0) {
    // A flying vehicle: where it was, is and will be, in height (the map
    // is seen from above).
    std::snprintf(label, sizeof label, "height: was %.2f, now %.2f, in 1 s %.2f m",
                  static_cast<double>(pr.reported.z), static_cast<double>(pr.predicted.z),
                  static_cast<double>(pr.map_path[static_cast<size_t>(n - 1)].z));
    // Smaller where the panel is too narrow for it.
    double scale = 0.42 * frame.height / 576.0;
    int baseline = 0;
    const int wide = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width;
    if (wide > side - 24) scale *= static_cast<double>(side - 24) / wide;
    cv::putText(map_, label, cv::Point(20, side + 3 * line_h), cv::FONT_HERSHEY_SIMPLEX, scale,
                kGhostLine, 1, cv::LINE_AA);
  }
}

bool MapLayer::MapPoint(double x, double y, double& px, double& py) const {
  if (!drawn_) return false;
  px = panel_.x + ox_ + scale_ * x;
  py = panel_.y + oy_ - scale_ * y;
  return true;
}

}  // namespace haptel::view::layers
