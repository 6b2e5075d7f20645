#include "haptel/mediator/prediction_score.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "haptel/core/clock.hpp"
#include "haptel/mediator/lap_timer.hpp"

namespace haptel::mediator {

namespace {

/// The drawn value named `name` (DrawnReality::ForEach), NaN when none is.
double DrawnValue(const DrawnReality& drawn, const std::string& name) {
  double value = std::nan("");
  DrawnReality::ForEach(drawn, [&](const char* n, double v) {
    if (name == n) value = v;
  });
  return value;
}

}  // namespace

void ScorePrediction(const record::TruthRecord& truth, SessionResult& result) {
  RunRecord& rec = result.record;
  if (!truth.empty()) {
    const double start_s = NsToS(result.started_ns);
    const TruthAt truth_at = [&](double t_s, double& x, double& y, double& z) {
      if (!truth.Covers(start_s + t_s)) return false;
      const TruthRow row = truth.PoseAt(start_s + t_s);
      x = row.x;
      y = row.y;
      z = row.z;
      return true;
    };
    const ErrorPercentiles e = ScoreAgainstTruth(result.shown, truth_at, result.shown_height);
    rec.prediction_error_m_p50 = e.p50;
    rec.prediction_error_m_p95 = e.p95;
    // The robot's pose at each state's moment, localised or not, and its odometry.
    if (!result.located.empty()) {
      const ErrorPercentiles l = ScoreAgainstTruth(result.located, truth_at, false);
      const ErrorPercentiles o = ScoreAgainstTruth(result.odometry, truth_at, false);
      rec.localisation_error_m_p50 = l.p50;
      rec.localisation_error_m_p95 = l.p95;
      rec.odometry_error_m_p50 = o.p50;
      rec.odometry_error_m_p95 = o.p95;
    }
  }
  const DrawnReality& drawn = truth.params();
  // The battery's fade over the run (the speed never below half).
  double fade = 1.0;
  if (truth.rows().size() > 1) {
    const double minutes =
        NsToS(truth.rows().back().operator_ns - truth.rows().front().operator_ns) / 60.0;
    fade = std::max(0.5, 1.0 - drawn.battery_fade_per_min * minutes);
  }
  for (EstimatedParameter& p : rec.estimated) {
    p.truth = DrawnValue(drawn, p.name);
    if (p.name == "left_gain" || p.name == "right_gain") p.truth *= fade;
  }
}

void JudgeLapOnTruth(const record::TruthRecord& truth, const Track& track, SessionResult& result) {
  record::TruthLap& lap = result.record.truth_lap;
  lap = {};
  if (truth.empty()) return;
  LapTimer timer(track);
  for (const TruthRow& row : truth.rows())
    timer.Update(NsToS(row.operator_ns - result.started_ns), Vec2(row.x, row.y));
  lap.judged = true;
  lap.completed = timer.completed();
  lap.lap_time_s = timer.completed() ? timer.lap_time_s() : std::nan("");
  const RunRecord& live = result.record;
  if (!timer.completed() && timer.started() && timer.next_gate() == timer.gates_total() &&
      live.completed && std::isfinite(live.approach_s)) {
    // The run ended as the odometry crossed the finish; the robot truly
    // short of it then: the rest of the way at its true speed.
    constexpr double kMaxProjectedM = 0.5;
    const double end_s = live.approach_s + live.lap_time_s;
    const TruthRow at = truth.PoseAt(NsToS(result.started_ns) + end_s);
    const Vec2 forward = track.TangentAt(0.0);
    const double rest = (track.PointAt(0.0) - Vec2(at.x, at.y)).dot(forward);
    const double speed = at.speed * std::cos(at.heading - std::atan2(forward.y(), forward.x()));
    if (rest >= 0.0 && rest <= kMaxProjectedM && speed > 0.02) {
      lap.completed = true;
      lap.projected = true;
      lap.lap_time_s = end_s + rest / speed - timer.start_t_s();
    }
  }
  lap.gates_passed = timer.gates_passed();
  lap.gates_missed = timer.gates_missed();
  lap.splits = timer.splits();
}

std::vector<std::string> TruthLapDisagreements(const RunRecord& record) {
  std::vector<std::string> lines;
  if (!record.truth_lap.judged) return lines;
  const std::vector<GateSplit>& truth = record.truth_lap.splits;
  const auto what = [](const GateSplit& s) {
    return s.split_s < 0.0 ? "never reached it" : s.passed ? "passed it" : "missed it";
  };
  for (size_t i = 0; i < record.splits.size() && i < truth.size(); ++i) {
    const GateSplit& live = record.splits[i];
    const GateSplit& real = truth[i];
    if (live.passed == real.passed && (live.split_s < 0.0) == (real.split_s < 0.0)) continue;
    lines.push_back("gate " + std::to_string(live.gate + 1) + ": the odometry " + what(live) +
                    ", the vehicle truly " + what(real));
  }
  return lines;
}

}  // namespace haptel::mediator
