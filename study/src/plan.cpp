#include "haptel/study/plan.hpp"

#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/study/design.hpp"

namespace haptel::study {

std::vector<PlannedTrial> PlanTrials(const StudyConfig& config) {
  OrderDesign design;
  design.kind = config.order == StudyOrder::kBalancedLatinSquare ? OrderDesignKind::kBalancedLatinSquare
                : config.order == StudyOrder::kRandom            ? OrderDesignKind::kRandom
                                                                 : OrderDesignKind::kFixed;
  design.conditions = static_cast<int>(config.conditions.size());
  design.participants = static_cast<int>(config.participants.size());
  design.repetitions = config.repetitions;
  design.seed = config.seed;
  for (int i = 0; i < design.conditions; ++i) design.fixed_order.push_back(i);
  ConditionOrders orders;
  if (config.participants.empty()) return {};  // a person study adds them later
  try {
    orders = MakeConditionOrders(design);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(config.file.string() + ": key 'design': " + e.what());
  }
  std::vector<PlannedTrial> plan;
  for (size_t p = 0; p < orders.size(); ++p) {
    const size_t per_repetition = config.conditions.size();
    for (size_t i = 0; i < orders[p].size(); ++i) {
      const StudyCondition& condition = config.conditions.at(static_cast<size_t>(orders[p][i]));
      plan.push_back({config.participants[p].id, static_cast<int>(i) + 1, condition.name,
                      static_cast<int>(i / per_repetition) + 1});
    }
  }
  return plan;
}

}  // namespace haptel::study
