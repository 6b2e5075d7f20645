#include "haptel/mediator/prediction.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::mediator {

std::string_view PredictionModelName(PredictionModel model) {
  return model == PredictionModel::kLearn ? "learn" : "nominal";
}

ErrorPercentiles PercentilesOf(std::vector<double> errors_m) {
  ErrorPercentiles out;
  out.count = errors_m.size();
  if (errors_m.empty()) return out;
  std::sort(errors_m.begin(), errors_m.end());
  const auto nearest_rank = [&](double p) {
    const auto rank = static_cast<size_t>(std::ceil(p * static_cast<double>(errors_m.size())));
    return errors_m[std::clamp<size_t>(rank, 1, errors_m.size()) - 1];
  };
  out.p50 = nearest_rank(0.50);
  out.p95 = nearest_rank(0.95);
  return out;
}

ErrorPercentiles ScoreAgainstTruth(const std::vector<ShownPose>& shown, const TruthAt& truth_at,
                                   bool with_height) {
  std::vector<double> errors_m;
  errors_m.reserve(shown.size());
  for (const ShownPose& p : shown) {
    double x = 0.0, y = 0.0, z = 0.0;
    if (!truth_at(p.t_s, x, y, z)) continue;
    const double dz = with_height ? p.z - z : 0.0;
    errors_m.push_back(std::sqrt((p.x - x) * (p.x - x) + (p.y - y) * (p.y - y) + dz * dz));
  }
  return PercentilesOf(std::move(errors_m));
}

}  // namespace haptel::mediator
