#include "haptel/study/plan.hpp"

#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/study/design.hpp"

namespace haptel::study {

std::vector<PlannedTrial> PlanTrials(const StudyConfig& config) {
  OrderDesign design;
  design.kind = config.order == StudyOrder::kBalancedLatinSquare
                    ? OrderDesignKind::kBalancedLatinSquare
                : config.order == StudyOrder::kRandom ? OrderDesignKind::kRandom
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
                      static_cast<int>(i / per_repetition) + 1, condition.device_name});
    }
  }
  return plan;
}

std::vector<PlannedTrial> PlanParticipant(const StudyConfig& config, const std::string& id,
                                          int row_index) {
  const int k = static_cast<int>(config.conditions.size());
  std::vector<int> order;
  switch (config.order) {
    case StudyOrder::kBalancedLatinSquare: {
      const std::vector<std::vector<int>> rows = WilliamsRows(k);
      order = rows[static_cast<size_t>(row_index) % rows.size()];
      break;
    }
    case StudyOrder::kRandom:
      // Earlier participants' orders do not change as participants are added.
      order = RandomOrders(k, row_index + 1, config.seed).back();
      break;
    case StudyOrder::kFixed:
      for (int i = 0; i < k; ++i) order.push_back(i);
      break;
  }
  std::vector<PlannedTrial> trials;
  for (int r = 0; r < config.repetitions; ++r) {
    for (const int c : order) {
      const StudyCondition& condition = config.conditions.at(static_cast<size_t>(c));
      trials.push_back(
          {id, static_cast<int>(trials.size()) + 1, condition.name, r + 1, condition.device_name});
    }
  }
  return trials;
}

int BlockSize(const StudyConfig& config) {
  if (config.order != StudyOrder::kBalancedLatinSquare) return 1;
  return static_cast<int>(WilliamsRows(static_cast<int>(config.conditions.size())).size());
}

}  // namespace haptel::study
