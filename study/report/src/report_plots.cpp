// The report's plots, drawn with OpenCV (as the run pictures are): plain
// axes, one colour per participant, labels in the plot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "haptel/study/report.hpp"

namespace haptel::study {
namespace {

constexpr int kWidth = 900;
constexpr int kHeight = 520;
constexpr int kLeft = 80, kRight = 30, kTop = 60, kBottom = 70;
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(220, 220, 220);

/// A qualitative palette (BGR).
cv::Scalar Colour(size_t i) {
  static const cv::Scalar kPalette[] = {
      {180, 119, 31}, {14, 127, 255},  {44, 160, 44},   {40, 39, 214},  {189, 103, 148},
      {75, 86, 140},  {194, 119, 227}, {127, 127, 127}, {34, 189, 188}, {207, 190, 23}};
  return kPalette[i % std::size(kPalette)];
}

std::string Text(double value, int decimals) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

void Label(cv::Mat& image, const std::string& text, cv::Point at, double scale = 0.5,
           bool centred = false) {
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline);
  if (centred) at.x -= size.width / 2;
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, kInk, 1, cv::LINE_AA);
}

/// Axes with a y range and tick labels; returns y(value) → pixel row.
struct Frame {
  double y_min, y_max;
  int Y(double v) const {
    return kTop + static_cast<int>(
                      std::lround((y_max - v) / (y_max - y_min) * (kHeight - kTop - kBottom)));
  }
  int X(size_t i, size_t n) const {
    const double step = static_cast<double>(kWidth - kLeft - kRight) / static_cast<double>(n);
    return kLeft + static_cast<int>(std::lround(step * (static_cast<double>(i) + 0.5)));
  }
};

Frame Axes(cv::Mat& image, const std::string& title, const std::string& y_label, double y_min,
           double y_max, const std::vector<std::string>& categories) {
  Frame f{y_min, y_max};
  Label(image, title, {kLeft, 22}, 0.6);
  const double span = y_max - y_min;
  const double raw = span / 6.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double step = raw / magnitude < 2   ? 2 * magnitude
                      : raw / magnitude < 5 ? 5 * magnitude
                                            : 10 * magnitude;
  for (double v = std::ceil(y_min / step) * step; v <= y_max + 1e-9; v += step) {
    cv::line(image, {kLeft, f.Y(v)}, {kWidth - kRight, f.Y(v)}, kGrid, 1);
    Label(image, Text(v, step < 1 ? 1 : 0), {8, f.Y(v) + 5}, 0.45);
  }
  cv::line(image, {kLeft, kTop}, {kLeft, kHeight - kBottom}, kInk, 1);
  cv::line(image, {kLeft, kHeight - kBottom}, {kWidth - kRight, kHeight - kBottom}, kInk, 1);
  Label(image, y_label, {8, kTop - 4}, 0.45);
  for (size_t i = 0; i < categories.size(); ++i) {
    Label(image, categories[i], {f.X(i, categories.size()), kHeight - kBottom + 22}, 0.5, true);
  }
  return f;
}

void Save(const cv::Mat& image, const std::filesystem::path& png) {
  if (!cv::imwrite(png.string(), image)) throw std::runtime_error("cannot write " + png.string());
}

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double at = q * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(at));
  const size_t hi = std::min(v.size() - 1, lo + 1);
  return v[lo] + (v[hi] - v[lo]) * (at - static_cast<double>(lo));
}

/// Whether any of `participant`'s trials of `condition` stopped at the cap
/// (an unfinished lap, scored at the cap): its point is not a lap time.
bool Capped(const StudyResults& results, const std::string& participant,
            const std::string& condition) {
  for (const StudyResults::Trial& t : results.trials) {
    if (t.participant == participant && t.condition == condition && !t.completed) return true;
  }
  return false;
}

/// A capped point: a hollow square crossed, in the participant's colour, so
/// that it reads apart from a finished lap's dot even in grey print.
void CappedMarker(cv::Mat& image, cv::Point at, const cv::Scalar& colour) {
  constexpr int r = 7;
  cv::rectangle(image, {at.x - r, at.y - r}, {at.x + r, at.y + r}, cv::Scalar(255, 255, 255),
                cv::FILLED);
  cv::rectangle(image, {at.x - r, at.y - r}, {at.x + r, at.y + r}, colour, 2, cv::LINE_AA);
  cv::line(image, {at.x - r, at.y - r}, {at.x + r, at.y + r}, colour, 1, cv::LINE_AA);
  cv::line(image, {at.x - r, at.y + r}, {at.x + r, at.y - r}, colour, 1, cv::LINE_AA);
}

}  // namespace

void DrawLapTimes(const StudyResults& results, const StudyReport& report,
                  const std::filesystem::path& png) {
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  double top = 1.0;
  for (const ConditionSummary& c : report.conditions) {
    for (const double v : c.lap_time_s) {
      if (std::isfinite(v)) top = std::max(top, v);
    }
  }
  std::vector<std::string> names;
  for (const ConditionSummary& c : report.conditions) names.push_back(c.name);
  const Frame f =
      Axes(image, "Lap time per condition (box: quartiles, whiskers: range; lines: participants)",
           "lap time (s)", 0.0, top * 1.1, names);
  const size_t k = report.conditions.size();
  const int half =
      std::max(8, (kWidth - kLeft - kRight) / static_cast<int>(std::max<size_t>(k, 1)) / 5);
  for (size_t c = 0; c < k; ++c) {
    std::vector<double> values;
    for (const double v : report.conditions[c].lap_time_s) {
      if (std::isfinite(v)) values.push_back(v);
    }
    if (values.empty()) continue;
    const int x = f.X(c, k);
    cv::line(image, {x, f.Y(Quantile(values, 0.0))}, {x, f.Y(Quantile(values, 1.0))}, kInk, 1);
    cv::rectangle(image, {x - half, f.Y(Quantile(values, 0.75))},
                  {x + half, f.Y(Quantile(values, 0.25))}, cv::Scalar(235, 225, 210), cv::FILLED);
    cv::rectangle(image, {x - half, f.Y(Quantile(values, 0.75))},
                  {x + half, f.Y(Quantile(values, 0.25))}, kInk, 1);
    cv::line(image, {x - half, f.Y(Quantile(values, 0.5))}, {x + half, f.Y(Quantile(values, 0.5))},
             kInk, 2);
  }
  bool any_capped = false;
  for (size_t p = 0; p < results.participants.size(); ++p) {
    cv::Point previous(-1, -1);
    for (size_t c = 0; c < k; ++c) {
      const double v = report.conditions[c].lap_time_s[p];
      if (!std::isfinite(v)) {
        previous = {-1, -1};
        continue;
      }
      const cv::Point at(f.X(c, k), f.Y(v));
      if (previous.x >= 0) cv::line(image, previous, at, Colour(p), 2, cv::LINE_AA);
      if (Capped(results, results.participants[p], report.conditions[c].name)) {
        CappedMarker(image, at, Colour(p));
        any_capped = true;
      } else {
        cv::circle(image, at, 4, Colour(p), cv::FILLED, cv::LINE_AA);
      }
      previous = at;
    }
    const int y = kHeight - 25;
    const int x = kLeft + static_cast<int>(p) * 90;
    cv::line(image, {x, y - 4}, {x + 20, y - 4}, Colour(p), 2);
    Label(image, results.participants[p], {x + 25, y}, 0.45);
  }
  if (any_capped) {
    // The legend's own entry, at the right of the participants'.
    const int x = kWidth - kRight - 230;
    const int y = kHeight - 25;
    CappedMarker(image, {x + 8, y - 4}, kInk);
    Label(image, "capped: scored at the " + Text(results.trial_cap_s, 0) + " s cap", {x + 22, y},
          0.45);
  }
  Save(image, png);
}

void DrawRanks(const StudyReport& report, const std::filesystem::path& png) {
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const size_t k = report.conditions.size();
  std::vector<std::string> names;
  for (const ConditionSummary& c : report.conditions) names.push_back(c.name);
  const Frame f = Axes(image, "Mean rank per condition (1 = fastest)", "mean rank", 0.0,
                       static_cast<double>(std::max<size_t>(k, 1)) + 0.5, names);
  const int half =
      std::max(8, (kWidth - kLeft - kRight) / static_cast<int>(std::max<size_t>(k, 1)) / 4);
  for (size_t c = 0; c < k; ++c) {
    const double rank = report.conditions[c].mean_rank;
    if (!std::isfinite(rank)) continue;
    const int x = f.X(c, k);
    cv::rectangle(image, {x - half, f.Y(rank)}, {x + half, f.Y(0.0)}, Colour(c), cv::FILLED);
    Label(image, Text(rank, 2), {x, f.Y(rank) - 6}, 0.5, true);
  }
  if (report.analysis && !report.analysis->post_hoc.pairs.empty() &&
      report.analysis->post_hoc.pairs[0].critical_difference) {
    // The Nemenyi critical difference, drawn to the ranks' scale: bars whose
    // tops differ by more are significantly different.
    const double cd = *report.analysis->post_hoc.pairs[0].critical_difference;
    const int x = kWidth - kRight - 20;
    const double from = static_cast<double>(k) + 0.3;
    cv::line(image, {x, f.Y(from)}, {x, f.Y(from - cd)}, kInk, 2);
    cv::line(image, {x - 6, f.Y(from)}, {x + 6, f.Y(from)}, kInk, 2);
    cv::line(image, {x - 6, f.Y(from - cd)}, {x + 6, f.Y(from - cd)}, kInk, 2);
    Label(image, "CD " + Text(cd, 2), {x - 75, f.Y(from - cd / 2)}, 0.45);
  }
  Save(image, png);
}

bool DrawRatings(const StudyResults& results, const std::filesystem::path& png) {
  // Mean score per questionnaire and condition.
  std::map<std::string, std::map<std::string, std::pair<double, int>>> scores;
  for (const StudyResults::Answer& a : results.answers) {
    if (a.item != "score") continue;
    char* end = nullptr;
    const double v = std::strtod(a.value.c_str(), &end);
    if (end == a.value.c_str() || !std::isfinite(v)) continue;
    auto& s = scores[a.questionnaire][a.condition];
    s.first += v;
    s.second += 1;
  }
  if (scores.empty()) return false;
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  double top = 1.0;
  for (const auto& [q, by_condition] : scores) {
    for (const auto& [c, s] : by_condition) top = std::max(top, s.first / s.second);
  }
  const Frame f = Axes(image, "Questionnaire scores per condition (mean)", "score", 0.0, top * 1.15,
                       results.conditions);
  const size_t k = results.conditions.size();
  const int group = (kWidth - kLeft - kRight) / static_cast<int>(std::max<size_t>(k, 1));
  const int bar = std::max(4, group / static_cast<int>(scores.size() + 1) - 4);
  size_t qi = 0;
  for (const auto& [q, by_condition] : scores) {
    for (size_t c = 0; c < k; ++c) {
      const auto it = by_condition.find(results.conditions[c]);
      if (it == by_condition.end()) continue;
      const double mean = it->second.first / it->second.second;
      const int x = f.X(c, k) - group / 2 + 6 + static_cast<int>(qi) * (bar + 4);
      cv::rectangle(image, {x, f.Y(mean)}, {x + bar, f.Y(0.0)}, Colour(qi), cv::FILLED);
      Label(image, Text(mean, 1), {x + bar / 2, f.Y(mean) - 5}, 0.4, true);
    }
    const int y = kHeight - 25;
    const int x = kLeft + static_cast<int>(qi) * 140;
    cv::rectangle(image, {x, y - 10}, {x + 14, y}, Colour(qi), cv::FILLED);
    Label(image, q, {x + 20, y}, 0.45);
    ++qi;
  }
  Save(image, png);
  return true;
}

bool DrawModelMeans(const StudyResults& results, const StudyReport& report,
                    const std::filesystem::path& png) {
  if (!report.mixed_model) return false;
  const MixedModelResult& m = *report.mixed_model;
  // Back-transformed from the log scale: geometric-mean lap times in s; the
  // interval is asymmetric around the point, as it should be.
  double top = results.reference_lap_s.value_or(1.0);
  for (const MixedModelCondition& c : m.conditions) {
    if (c.mean) top = std::max(top, std::exp(c.mean->ci_high));
  }
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const Frame f = Axes(image,
                       "Mixed model: estimated mean lap time, 95 % CI (at position " +
                           Text(m.mean_position, 1) + ")",
                       "lap time (s)", 0.0, top * 1.15, results.conditions);
  const size_t k = results.conditions.size();
  if (results.reference_lap_s) {
    // The baseline, dashed across the plot.
    const int y = f.Y(*results.reference_lap_s);
    for (int x = kLeft; x < kWidth - kRight; x += 16)
      cv::line(image, {x, y}, {std::min(x + 9, kWidth - kRight), y}, kInk, 1);
    Label(image, "reference lap " + Text(*results.reference_lap_s, 0) + " s", {kLeft + 6, y - 6},
          0.45);
  }
  for (size_t c = 0; c < k && c < m.conditions.size(); ++c) {
    const int x = f.X(c, k);
    if (!m.conditions[c].mean) {
      Label(image, "no trials", {x, f.Y(0.0) - 8}, 0.45, true);
      continue;
    }
    const MixedModelContrast& mean = *m.conditions[c].mean;
    const int low = f.Y(std::exp(mean.ci_low));
    const int high = f.Y(std::exp(mean.ci_high));
    cv::line(image, {x, low}, {x, high}, Colour(c), 2, cv::LINE_AA);
    cv::line(image, {x - 10, low}, {x + 10, low}, Colour(c), 2);
    cv::line(image, {x - 10, high}, {x + 10, high}, Colour(c), 2);
    cv::circle(image, {x, f.Y(std::exp(mean.estimate))}, 6, Colour(c), cv::FILLED, cv::LINE_AA);
    const std::string label =
        Text(std::exp(mean.estimate), 1) + " s" + (m.conditions[c].reference ? " (reference)" : "");
    Label(image, label, {x + 14, f.Y(std::exp(mean.estimate)) + 5}, 0.45);
  }
  Save(image, png);
  return true;
}

}  // namespace haptel::study

namespace haptel::study {

void DrawPowerCurve(const PowerResult& power, const std::string& title,
                    const std::filesystem::path& png) {
  cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<std::string> counts;
  for (const PowerPoint& p : power.points) counts.push_back(std::to_string(p.participants));
  const Frame f = Axes(image, title, "power", 0.0, 1.05, counts);
  Label(image, "participants", {kWidth / 2, kHeight - 18}, 0.5, true);
  // The target, dashed across the plot.
  const int target_y = f.Y(power.target_power);
  for (int x = kLeft; x < kWidth - kRight; x += 16) {
    cv::line(image, {x, target_y}, {std::min(x + 9, kWidth - kRight), target_y}, kInk, 1);
  }
  Label(image, "target " + Text(100.0 * power.target_power, 0) + " %", {kLeft + 6, target_y - 6},
        0.45);
  const size_t n = power.points.size();
  // Each test a line with its 95 % interval as whiskers, the two a few
  // pixels apart so the whiskers do not hide each other.
  struct Test {
    const char* name;
    double PowerPoint::*value;
    BinomialInterval PowerPoint::*interval;
    int shift;
  };
  const Test tests[] = {
      {kPowerFriedmanLegend, &PowerPoint::friedman_power, &PowerPoint::friedman_interval, -5},
      {kPowerMixedModelLegend, &PowerPoint::lmm_power, &PowerPoint::lmm_interval, 5}};
  for (size_t t = 0; t < std::size(tests); ++t) {
    const cv::Scalar colour = Colour(t);
    cv::Point previous;
    for (size_t i = 0; i < n; ++i) {
      const PowerPoint& p = power.points[i];
      const int x = f.X(i, n) + tests[t].shift;
      const cv::Point at(x, f.Y(p.*tests[t].value));
      const BinomialInterval& ci = p.*tests[t].interval;
      cv::line(image, {x, f.Y(ci.low)}, {x, f.Y(ci.high)}, colour, 1, cv::LINE_AA);
      cv::line(image, {x - 5, f.Y(ci.low)}, {x + 5, f.Y(ci.low)}, colour, 1);
      cv::line(image, {x - 5, f.Y(ci.high)}, {x + 5, f.Y(ci.high)}, colour, 1);
      if (i > 0) cv::line(image, previous, at, colour, 2, cv::LINE_AA);
      cv::circle(image, at, 5, colour, cv::FILLED, cv::LINE_AA);
      previous = at;
    }
    // Lower right: power curves rise to the right, so that corner is free.
    const int legend_y = kHeight - kBottom - 50 + 20 * static_cast<int>(t);
    cv::line(image, {kWidth - kRight - 290, legend_y - 5}, {kWidth - kRight - 260, legend_y - 5},
             colour, 2);
    Label(image, tests[t].name, {kWidth - kRight - 252, legend_y}, 0.45);
  }
  Save(image, png);
}

}  // namespace haptel::study
