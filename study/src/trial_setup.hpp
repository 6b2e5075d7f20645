#pragma once
// The session of one study trial, shared by `haptel study run` (study_run.cpp)
// and `haptel study power` (study_power.cpp), so both run a trial alike.
#include <filesystem>
#include <string>
#include <vector>

#include "haptel/config/study.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/study/store.hpp"

namespace haptel::study {

/// What `haptel run` would drive for `trial` of `config`: its track,
/// interface, operator (a synthetic participant drives with its profile from
/// config.profiles and `experience` trials done before), the cap on the
/// lap's clock, the study's link; in simulated time (`haptel run
/// --simulated-time`: one simulated clock for the whole process, so one such
/// trial at a time per process). Throws ConfigError/UsageError as `haptel run`.
mediator::SessionSetup TrialSetup(const StudyConfig& config, const PlannedTrial& trial,
                                  const std::filesystem::path& database, const std::string& domain, bool verbose,
                                  int experience, bool simulated_time);

}  // namespace haptel::study
