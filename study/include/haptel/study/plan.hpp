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

/// The trials of one participant added later (the console), the
/// `row_index`-th of the study (0-based, counting those in the file): the
/// same sequence PlanTrials would give them. A balanced Latin square is only
/// balanced over whole blocks of participants; BlockSize says how many.
std::vector<PlannedTrial> PlanParticipant(const StudyConfig& config, const std::string& id,
                                          int row_index);

/// Participants per balanced block: the Williams square's rows for a
/// balanced Latin square (k for even k, 2k for odd), 1 otherwise.
int BlockSize(const StudyConfig& config);

}  // namespace haptel::study
