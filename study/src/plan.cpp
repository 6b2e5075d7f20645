#include "haptel/study/plan.hpp"

namespace haptel::study {

// Placeholder until the design library lands: the conditions' order for all.
std::vector<PlannedTrial> PlanTrials(const StudyConfig& config) {
  std::vector<PlannedTrial> plan;
  for (const StudyParticipant& p : config.participants) {
    int position = 1;
    for (int r = 1; r <= config.repetitions; ++r) {
      for (const StudyCondition& c : config.conditions) plan.push_back({p.id, position++, c.name, r});
    }
  }
  return plan;
}

}  // namespace haptel::study
