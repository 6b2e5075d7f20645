#pragma once
/// @file A study's plan: which participant drives which condition at which
/// position, from the study's order design (study/stats: design.hpp).
#include <vector>

#include "haptel/config/study.hpp"
#include "haptel/study/store.hpp"

namespace haptel::study {

/// For each participant (in file order) the conditions in the design's order,
/// repeated `repetitions` times; positions 1, 2, ... Throws ConfigError naming
/// the study file and the key 'design' when the design does not fit the
/// participants (e.g. a balanced Latin square of 4 conditions for 3 people).
std::vector<PlannedTrial> PlanTrials(const StudyConfig& config);

}  // namespace haptel::study
