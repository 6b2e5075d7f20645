// The sessions a study runs: a person's practice lap shows a simulated robot
// in the third person as well as through its camera; a trial never does.
#include <catch2/catch.hpp>

#include "haptel/config/study.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/study_sessions.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

TEST_CASE("A practice lap shows the simulated robot in the third person; a trial does not") {
  const StudyConfig config = LoadStudy("config/studies/grand-prix-synthetic.yaml");
  const std::vector<PlannedTrial> plan = PlanTrials(config);
  REQUIRE_FALSE(plan.empty());
  const auto dir = test::ScratchDir("study-sessions");
  const mediator::SessionSetup trial =
      TrialSetup(config, plan.front(), dir / "study.db", "", false, 0, false);
  REQUIRE(trial.vehicle.kind == "sim-robot");
  CHECK_FALSE(trial.third_person);
  CHECK_FALSE(trial.direct_view);
  CHECK_FALSE(trial.single_interface);

  // The same session made a practice lap: the keyboard's direct view, the
  // participant in the title, and the chase camera beside the picture.
  mediator::SessionSetup practice = trial;
  MakePracticeLap(practice, "P3");
  CHECK(practice.third_person);
  CHECK(practice.direct_view);
  CHECK(practice.single_interface);
  CHECK(practice.title == "Haptel - practice lap - P3");

  // A real robot is in the room to be seen: no chase camera of a track
  // that is only a guess for it.
  mediator::SessionSetup real = trial;
  real.vehicle = LoadVehicle("config/vehicles/can-robot.yaml");
  MakePracticeLap(real, "P3");
  CHECK_FALSE(real.third_person);
  CHECK(real.direct_view);
}
