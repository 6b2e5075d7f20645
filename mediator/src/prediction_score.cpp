#include "haptel/mediator/prediction_score.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "haptel/core/clock.hpp"

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

}  // namespace haptel::mediator
