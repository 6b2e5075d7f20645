#include "overlay_layer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

namespace haptel::view {

namespace {
constexpr double kIndicatorHz = 1.5;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
}  // namespace

std::vector<std::string> OverlayLines(const Overlay& o) {
  std::vector<std::string> lines;
  char line[160];
  std::snprintf(line, sizeof line, "%s  (%s)", o.interface_name, o.operator_name);
  lines.emplace_back(line);
  if (o.lap_time_s >= 0) {
    if (o.time_left_s >= 0) {
      std::snprintf(line, sizeof line, "lap %.1f s   time left %.0f s", o.lap_time_s,
                    o.time_left_s);
    } else {
      std::snprintf(line, sizeof line, "lap %.1f s", o.lap_time_s);
    }
    lines.emplace_back(line);
    std::snprintf(line, sizeof line, "gates %d/%d   obstacles %d", o.gates_passed, o.gates_total,
                  o.obstacles_touched);
    lines.emplace_back(line);
    std::snprintf(line, sizeof line, "last contact: %s",
                  o.last_contact[0] != '\0' ? o.last_contact : "none");
    lines.emplace_back(line);
  } else if (o.time_left_s >= 0) {
    std::snprintf(line, sizeof line, "%.0f s   time left %.0f s", o.t_s, o.time_left_s);
    lines.emplace_back(line);
  }
  if (o.status[0] != '\0') lines.emplace_back(o.status);
  if (o.hud) {
    lines.push_back("speed " + HudSpeedText(o));
    if (o.throttle_locked) lines.emplace_back("THROTTLE LOCKED");
  }
  if (o.guidance_shown) {
    const double push = std::hypot(o.guidance_forward_n, o.guidance_left_n);
    if (o.guidance_ttc_s >= 0.0) {
      std::snprintf(line, sizeof line, "shared control: push %.1f N, obstacle in %.1f s", push,
                    o.guidance_ttc_s);
    } else {
      std::snprintf(line, sizeof line, "shared control: clear");
    }
    lines.emplace_back(line);
  }
  if (o.message[0] != '\0') lines.emplace_back(o.message);
  return lines;
}

GuidanceDial GuidanceDialOf(const Overlay& o, int width, int height) {
  GuidanceDial d;
  d.radius = static_cast<int>(50 * height / 576.0);
  d.centre_x = d.radius + 24;
  d.centre_y = height - d.radius - 24;
  (void)width;  // the dial keeps to the left edge whatever the width
  const double push = std::hypot(o.guidance_forward_n, o.guidance_left_n);
  const double fraction = std::min(1.0, push / std::max(o.guidance_max_n, 1e-6));
  const double norm = std::max(push, 1e-12);
  // Forward (x) is up the screen, left (y) is left: a push back points down.
  d.tip_x =
      d.centre_x - static_cast<int>(std::lround(d.radius * fraction * o.guidance_left_n / norm));
  d.tip_y =
      d.centre_y - static_cast<int>(std::lround(d.radius * fraction * o.guidance_forward_n / norm));
  return d;
}

std::string HudSpeedText(const Overlay& o) {
  if (!o.hud) return {};
  char text[32];
  std::snprintf(text, sizeof text, "%.2f m/s", std::abs(o.speed_mps));
  return text;
}

bool IndicatorLit(double t_s) {
  const double phase = t_s * kIndicatorHz;
  return phase - std::floor(phase) < 0.5;
}

namespace layers {

OverlayLayer::OverlayLayer(int width, int height, const TexturedQuads& quads)
    : width_(width), height_(height), quads_(quads), texture_(MakeTexture()) {
  bitmap_ = cv::Mat(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  UploadBgra(bitmap_);
}

OverlayLayer::~OverlayLayer() { glDeleteTextures(1, &texture_); }

void OverlayLayer::Draw(const ViewModel& model, const Frame& frame) {
  const Overlay& o = model.overlay;
  const bool lit = IndicatorLit(frame.t_s);
  const std::vector<std::string> lines = OverlayLines(o);
  std::string key;
  for (const auto& l : lines) key += l + '\n';
  key += o.contact_now ? 'C' : '-';
  key += (o.hud && o.turn_left && lit) ? 'L' : '-';
  key += (o.hud && o.turn_right && lit) ? 'R' : '-';
  char needle[16];
  std::snprintf(needle, sizeof needle, "%.3f",
                o.hud ? o.speed_mps / std::max(o.speed_max_mps, 1e-3) : 0.0);
  key += needle;
  if (o.guidance_shown) {
    // The arrow's tip, formatted like the needle (GCC 12's -Wrestrict misreads
    // `"G" + std::to_string(...)` here).
    const GuidanceDial dial = GuidanceDialOf(o, width_, height_);
    char tip[32];
    std::snprintf(tip, sizeof tip, "G%d,%d", dial.tip_x, dial.tip_y);
    key += tip;
  }
  glBindTexture(GL_TEXTURE_2D, texture_);
  if (key != key_) {
    key_ = key;
    Rasterise(o, lines, lit);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_BGRA, GL_UNSIGNED_BYTE,
                    bitmap_.data);
  }
  quads_.BeginOverWorld();
  const float w = static_cast<float>(width_), h = static_cast<float>(height_);
  for (const cv::Rect& r : drawn_) {
    quads_.DrawPixels(r, width_, height_,
                      {static_cast<float>(r.x) / w, static_cast<float>(r.y) / h,
                       static_cast<float>(r.width) / w, static_cast<float>(r.height) / h});
  }
}

void OverlayLayer::Rasterise(const Overlay& o, const std::vector<std::string>& lines, bool lit) {
  bitmap_.setTo(cv::Scalar(0, 0, 0, 0));
  drawn_.clear();
  RasterisePanel(o, lines);
  if (o.hud) RasteriseSpeedometer(o, lit);
  if (o.guidance_shown) RasteriseGuidance(o);
  if (o.message[0] != '\0') RasteriseMessage(o);
  if (o.contact_now) RasteriseContact();
  const cv::Rect frame(0, 0, width_, height_);
  for (cv::Rect& r : drawn_) r &= frame;
}

void OverlayLayer::RasterisePanel(const Overlay& o, const std::vector<std::string>& lines) {
  const double scale = 0.55 * height_ / 576.0;
  const int line_h = static_cast<int>(26 * height_ / 576.0);
  const int panel_lines = o.status[0] != '\0' ? 5 : 4;
  const cv::Rect panel(8, 8, static_cast<int>(width_ * 0.36), line_h * panel_lines + 12);
  cv::rectangle(bitmap_, panel, Bgra(0, 0, 0, 150), cv::FILLED);
  drawn_.push_back(panel);
  for (int i = 0; i < panel_lines && i < static_cast<int>(lines.size()); ++i) {
    cv::putText(bitmap_, lines[i], cv::Point(16, 8 + line_h * (i + 1)), kFont, scale,
                Bgra(255, 255, 255), 1, cv::LINE_AA);
  }
}

void OverlayLayer::RasteriseSpeedometer(const Overlay& o, bool lit) {
  // A 240° dial at the bottom right (clear of the wheel), the indicators
  // above it, left and right.
  cv::Mat& ov = bitmap_;
  const double scale = 0.55 * height_ / 576.0;
  const int radius = static_cast<int>(58 * height_ / 576.0);
  const cv::Point centre(width_ - radius - 24, height_ - radius - 16);
  drawn_.emplace_back(centre.x - radius - 10, centre.y - radius - 60, 2 * radius + 20,
                      2 * radius + 70);
  cv::circle(ov, centre, radius + 6, Bgra(20, 20, 20, 190), cv::FILLED, cv::LINE_AA);
  cv::ellipse(ov, centre, cv::Size(radius, radius), 0, 150, 390, Bgra(200, 200, 200), 2,
              cv::LINE_AA);
  const double fraction =
      std::clamp(std::abs(o.speed_mps) / std::max(o.speed_max_mps, 1e-3), 0.0, 1.0);
  const double angle = (150.0 + 240.0 * fraction) * M_PI / 180.0;
  cv::line(ov, centre,
           centre + cv::Point(static_cast<int>(radius * 0.85 * std::cos(angle)),
                              static_cast<int>(radius * 0.85 * std::sin(angle))),
           Bgra(40, 80, 255), 3, cv::LINE_AA);
  const std::string speed = HudSpeedText(o);
  int base = 0;
  const cv::Size ts = cv::getTextSize(speed, kFont, scale, 1, &base);
  cv::putText(ov, speed, centre + cv::Point(-ts.width / 2, radius / 2 + ts.height / 2), kFont,
              scale, Bgra(255, 255, 255), 1, cv::LINE_AA);
  auto arrow = [&](int direction, bool on) {  // direction −1: left
    const cv::Point tip(centre.x + direction * (radius - 4), centre.y - radius - 34);
    const cv::Point pts[3] = {tip, tip + cv::Point(-direction * 26, -16),
                              tip + cv::Point(-direction * 26, 16)};
    cv::fillConvexPoly(ov, pts, 3, on ? Bgra(60, 230, 60) : Bgra(60, 60, 60, 200), cv::LINE_AA);
  };
  arrow(-1, o.turn_left && lit);
  arrow(1, o.turn_right && lit);
  if (o.throttle_locked) {
    const cv::Point at(centre.x - radius - 190, height_ - 20);
    drawn_.emplace_back(at.x - 5, at.y - 25, 190, 35);
    cv::putText(ov, "THROTTLE LOCKED", at, kFont, scale, Bgra(0, 180, 255), 2, cv::LINE_AA);
  }
}

void OverlayLayer::RasteriseGuidance(const Overlay& o) {
  // Shared control's dial at the bottom left: the hand's plane seen from
  // above, the push on the hand as an orange arrow from its centre.
  const GuidanceDial d = GuidanceDialOf(o, width_, height_);
  const cv::Point centre(d.centre_x, d.centre_y), tip(d.tip_x, d.tip_y);
  drawn_.emplace_back(d.centre_x - d.radius - 8, d.centre_y - d.radius - 8, 2 * d.radius + 16,
                      2 * d.radius + 16);
  cv::circle(bitmap_, centre, d.radius + 6, Bgra(20, 20, 20, 190), cv::FILLED, cv::LINE_AA);
  cv::circle(bitmap_, centre, d.radius, Bgra(120, 120, 120), 1, cv::LINE_AA);
  cv::line(bitmap_, centre + cv::Point(0, -d.radius), centre + cv::Point(0, -d.radius + 8),
           Bgra(200, 200, 200), 2);
  if (tip != centre)
    cv::arrowedLine(bitmap_, centre, tip, Bgra(0, 140, 255), 4, cv::LINE_AA, 0, 0.3);
}

void OverlayLayer::RasteriseMessage(const Overlay& o) {
  const double scale = 0.55 * height_ / 576.0;
  int base = 0;
  const cv::Size ts = cv::getTextSize(o.message, kFont, scale * 1.2, 2, &base);
  const cv::Point at((width_ - ts.width) / 2, height_ - 24);
  const cv::Rect box(at.x - 8, at.y - ts.height - 8, ts.width + 16, ts.height + 16);
  cv::rectangle(bitmap_, box, Bgra(0, 0, 0, 160), cv::FILLED);
  drawn_.push_back(box);
  cv::putText(bitmap_, o.message, at, kFont, scale * 1.2, Bgra(255, 255, 255), 2, cv::LINE_AA);
}

void OverlayLayer::RasteriseContact() {
  cv::rectangle(bitmap_, cv::Rect(0, 0, width_, height_), Bgra(0, 0, 255, 220), 10);
  const int b = 8;
  drawn_.emplace_back(0, 0, width_, b);
  drawn_.emplace_back(0, height_ - b, width_, b);
  drawn_.emplace_back(0, 0, b, height_);
  drawn_.emplace_back(width_ - b, 0, b, height_);
}

}  // namespace layers
}  // namespace haptel::view
