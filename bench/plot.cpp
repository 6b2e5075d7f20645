#include "plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace haptel::bench {

std::filesystem::path BenchDir() {
  const std::filesystem::path dir = "build/bench";
  std::filesystem::create_directories(dir);
  return dir;
}

void PlotLines(const std::filesystem::path& file, const std::vector<Series>& series,
               const PlotOptions& o) {
  // The title on its own line above the y axis's label; the legend right
  // of the axes (over the lines it hid them), the picture that much wider.
  int text_w = 0;
  for (const Series& s : series) {
    int baseline = 0;
    text_w = std::max(text_w,
                      cv::getTextSize(s.name, cv::FONT_HERSHEY_SIMPLEX, 0.45, 1, &baseline).width);
  }
  const int legend_w = series.empty() ? 0 : text_w + 45;
  const int left = 80, right = 20, top = 60, bottom = 60;
  const int w = o.width - left - right, h = o.height - top - bottom;
  cv::Mat img(o.height, o.width + legend_w, CV_8UC3, cv::Scalar(255, 255, 255));
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  auto ty = [&](double y) { return o.log_y ? std::log10(std::max(y, 1e-12)) : y; };
  for (const Series& s : series) {
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (o.log_y && s.y[i] <= 0) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, ty(s.y[i]));
      y1 = std::max(y1, ty(s.y[i]));
    }
  }
  if (!(x1 > x0)) x1 = x0 + 1;
  if (!(y1 > y0)) y1 = y0 + 1;
  if (!o.log_y) y0 = std::min(y0, 0.0);
  auto px = [&](double x) { return left + static_cast<int>((x - x0) / (x1 - x0) * w); };
  auto py = [&](double y) { return top + h - static_cast<int>((ty(y) - y0) / (y1 - y0) * h); };
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200);
  cv::rectangle(img, {left, top}, {left + w, top + h}, black, 1);
  char buf[64];
  for (int k = 0; k <= 5; ++k) {
    const double xv = x0 + (x1 - x0) * k / 5;
    const int xp = left + w * k / 5;
    cv::line(img, {xp, top}, {xp, top + h}, grey, 1);
    std::snprintf(buf, sizeof buf, "%.4g", xv);
    cv::putText(img, buf, {xp - 20, top + h + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
                cv::LINE_AA);
    const double yv = y0 + (y1 - y0) * k / 5;
    const int yp = top + h - h * k / 5;
    cv::line(img, {left, yp}, {left + w, yp}, grey, 1);
    std::snprintf(buf, sizeof buf, "%.3g", o.log_y ? std::pow(10.0, yv) : yv);
    cv::putText(img, buf, {5, yp + 5}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  cv::putText(img, o.title, {left, 25}, cv::FONT_HERSHEY_SIMPLEX, 0.6, black, 1, cv::LINE_AA);
  cv::putText(img, o.x_label, {left + w / 2 - 60, o.height - 15}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
              black, 1, cv::LINE_AA);
  cv::putText(img, o.y_label + (o.log_y ? " (log)" : ""), {5, top - 8}, cv::FONT_HERSHEY_SIMPLEX,
              0.45, black, 1, cv::LINE_AA);
  // Ten distinguishable colours (BGR): a sweep of three realities by three modes fits.
  static const cv::Scalar kColours[] = {
      {200, 80, 30}, {30, 30, 200}, {40, 160, 40}, {160, 40, 160}, {0, 140, 220},
      {90, 90, 90},  {200, 200, 0}, {120, 60, 0},  {0, 90, 160},   {180, 120, 255}};
  constexpr size_t kColourCount = sizeof kColours / sizeof kColours[0];
  for (size_t k = 0; k < series.size(); ++k) {
    const cv::Scalar c = kColours[k % kColourCount];
    std::vector<cv::Point> pts;
    for (size_t i = 0; i < series[k].x.size() && i < series[k].y.size(); ++i) {
      if (o.log_y && series[k].y[i] <= 0) continue;
      pts.emplace_back(px(series[k].x[i]), py(series[k].y[i]));
    }
    if (pts.size() > 1) cv::polylines(img, pts, false, c, 2, cv::LINE_AA);
    for (const cv::Point& p : pts) cv::circle(img, p, 2, c, cv::FILLED);
  }
  const int legend_x = left + w + 15;
  for (size_t k = 0; k < series.size(); ++k) {
    const cv::Scalar c = kColours[k % kColourCount];
    const int ly = top + 20 + 20 * static_cast<int>(k);
    cv::line(img, {legend_x, ly - 4}, {legend_x + 25, ly - 4}, c, 2);
    cv::putText(img, series[k].name, {legend_x + 30, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
                cv::LINE_AA);
  }
  if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path());
  if (!cv::imwrite(file.string(), img))
    throw std::runtime_error("cannot write plot '" + file.string() + "'");
}

}  // namespace haptel::bench
