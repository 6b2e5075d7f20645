#pragma once
// A run record as a trial's session would save it, with only what the study
// reads set (lap, completion, obstacles): for the study's tests and fixture.
#include <string>

#include "haptel/record/recorder.hpp"

namespace haptel::test {

inline record::RunRecord TrialRun(double lap_s, bool completed = true, int obstacles = 0) {
  // Strings moved in, not assigned from literals: GCC 12 warns falsely
  // (-Wrestrict) on literal assignment once this is inlined into a main().
  record::RunRecord run;
  run.started_wall_ns = 1'714'566'896'000'000'000;
  run.config_name = std::string("study test");
  run.track = std::string("t");
  run.interface = std::string("i");
  run.vehicle = std::string("v");
  run.completed = completed;
  if (completed) {
    run.outcome = std::string("completed");
  } else {
    run.outcome = std::string("time limit");
  }
  run.lap_time_s = lap_s;
  run.obstacles_touched = obstacles;
  run.operator_kind = std::string("person");
  run.device = std::string("sim");
  return run;
}

}  // namespace haptel::test
