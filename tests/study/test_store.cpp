// The study's tables (StudyStore) on a real SQLite file, and the plan of a
// participant added later (PlanParticipant): what a kill between any two
// transactions leaves, a changed study refused, trials and answers never
// twice, participants added in the console after the file's.
#include <catch2/catch.hpp>

#include "haptel/record/recorder.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/study/plan.hpp"
#include "haptel/study/store.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// "P<n>", built piecewise: GCC 12 warns falsely (-Wrestrict) on "P" + string.
std::string Id(int n) {
  std::string id(1, 'P');
  id += std::to_string(n);
  return id;
}

StudyConfig FourConditions(const std::filesystem::path& dir, int participants) {
  StudyConfig config;
  config.file = dir / "s.yaml";
  test::WriteFile(config.file, "name: s\n");
  config.name = "store-study";
  config.operators = "person";
  config.conditions = {{"a", "cockpit"}, {"b", "cockpit-hud"}, {"c", "cockpit-assisted"}, {"d", "gesture"}};
  for (int i = 0; i < participants; ++i) config.participants.push_back({Id(i + 1), ""});
  return config;
}

std::vector<std::string> Conditions(const std::vector<PlannedTrial>& trials) {
  std::vector<std::string> names;
  for (const PlannedTrial& t : trials) names.push_back(t.condition);
  return names;
}

}  // namespace

TEST_CASE("A participant added later gets the sequence the file would have given them") {
  const auto dir = test::ScratchDir("study-store-plan");
  StudyConfig eight = FourConditions(dir, 8);
  const std::vector<PlannedTrial> full = PlanTrials(eight);
  StudyConfig none = FourConditions(dir, 0);
  for (int row = 0; row < 8; ++row) {
    const std::vector<PlannedTrial> one = PlanParticipant(none, Id(row + 1), row);
    REQUIRE(one.size() == 4);
    const std::vector<PlannedTrial> expected(full.begin() + row * 4, full.begin() + row * 4 + 4);
    CHECK(Conditions(one) == Conditions(expected));
    CHECK(one[3].position == 4);
  }
  CHECK(BlockSize(none) == 4);  // Williams: 4 rows for 4 conditions

  SECTION("random: earlier participants' orders do not change") {
    eight.order = none.order = StudyOrder::kRandom;
    eight.seed = none.seed = 99;
    const std::vector<PlannedTrial> shuffled = PlanTrials(eight);
    const std::vector<PlannedTrial> sixth = PlanParticipant(none, "P6", 5);
    CHECK(Conditions(sixth) == Conditions({shuffled.begin() + 20, shuffled.begin() + 24}));
    CHECK(BlockSize(none) == 1);
  }
  SECTION("repetitions run the whole sequence again") {
    none.repetitions = 2;
    const std::vector<PlannedTrial> twice = PlanParticipant(none, "P2", 1);
    REQUIRE(twice.size() == 8);
    CHECK(twice[4].condition == twice[0].condition);
    CHECK(twice[4].repetition == 2);
    CHECK(twice[7].position == 8);
  }
}

TEST_CASE("The store keeps a study's plan, trials and answers across restarts, each once") {
  const auto dir = test::ScratchDir("study-store");
  const StudyConfig config = FourConditions(dir, 4);
  const std::vector<PlannedTrial> plan = PlanTrials(config);
  const auto db = dir / "s.db";
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    CHECK_FALSE(store.resumed());
    CHECK(store.Plan().size() == 16);
    CHECK(store.Participants() == std::vector<std::string>{"P1", "P2", "P3", "P4"});
    REQUIRE(store.NextTrial());
    CHECK(store.NextTrial()->participant == "P1");
    CHECK(store.NextTrial()->position == 1);
    // A finished trial and an unfinished one, scored at the cap.
    recorder.Save(test::TrialRun(42.0, true, 2), store.TrialWriter(plan[0], 600.0));
    recorder.Save(test::TrialRun(700.0, false), store.TrialWriter(plan[1], 600.0));
    // A run that ended in a fault: recorded, but the trial is not done.
    record::RunRecord lost = test::TrialRun(5.1, false, 1);
    lost.outcome = mediator::ToString(mediator::Outcome::kVehicleLost);
    recorder.Save(lost, store.TrialWriter(plan[2], 600.0));
    CHECK(store.Trials().size() == 2);
    CHECK(store.NextTrial()->position == 3);
    CHECK(FinishesTrial("crashed"));  // the pilot's own doing: a finished, unfinished lap
    CHECK_FALSE(FinishesTrial("device lost"));
    CHECK_FALSE(FinishesTrial("interrupted"));
    // The same trial again: refused, and its run rolled back with it.
    const size_t runs = recorder.LoadAll().size();
    CHECK_THROWS(recorder.Save(test::TrialRun(40.0), store.TrialWriter(plan[0], 600.0)));
    CHECK(recorder.LoadAll().size() == runs);
  }
  // Restarted (a kill -9 leaves exactly what was committed).
  record::Recorder recorder(db);
  StudyStore store(recorder, config, plan);
  CHECK(store.resumed());
  const std::vector<TrialRow> trials = store.Trials();
  REQUIRE(trials.size() == 2);
  CHECK(trials[0].lap_time_s == 42.0);
  CHECK(trials[0].obstacles == 2);
  CHECK(trials[0].completed);
  CHECK(trials[1].lap_time_s == 600.0);  // the cap, as the thesis scored driver B
  CHECK_FALSE(trials[1].completed);
  CHECK(store.NextTrial()->position == 3);
  CHECK(store.TrialsDone("P1") == 2);
  CHECK(store.TrialsDone("P2") == 0);

  SECTION("answers: once per participant, condition and questionnaire") {
    CHECK_FALSE(store.Answered("P1", plan[0].condition, "thesis"));
    store.SaveAnswers("P1", plan[0].condition, "thesis", {{"easy_to_learn", "4"}, {"efficient", "3"}});
    CHECK(store.Answered("P1", plan[0].condition, "thesis"));
    CHECK_THROWS_AS(store.SaveAnswers("P1", plan[0].condition, "thesis", {{"easy_to_learn", "5"}}), AlreadyAnswered);
    CHECK(store.Answers().size() == 2);
  }
  SECTION("redo takes a trial back once; the next row is attempt 2") {
    CHECK(store.Redo("P1", 1, "test"));
    CHECK_FALSE(store.Redo("P1", 1, "test"));
    CHECK(store.NextTrial()->position == 1);
    recorder.Save(test::TrialRun(39.0), store.TrialWriter(plan[0], 600.0));
    CHECK(store.Trials()[0].attempt == 2);
  }
  SECTION("the practice lap is remembered per participant") {
    CHECK_FALSE(store.Practised("P2"));
    store.Event("practice", "P2", 0, "run 9");
    CHECK(store.Practised("P2"));
    CHECK_FALSE(store.Practised("P3"));
  }
  SECTION("a participant added in the console comes after the file's, and survives a restart") {
    store.AddParticipant("E", PlanParticipant(config, "E", 4));
    CHECK(store.Plan().size() == 20);
    CHECK(store.Participants().back() == "E");
    CHECK_THROWS_AS(store.AddParticipant("E", PlanParticipant(config, "E", 5)), AlreadyAnswered);
    CHECK_THROWS_AS(store.AddParticipant("P1", PlanParticipant(config, "P1", 5)), AlreadyAnswered);
    CHECK(store.Plan().size() == 20);
    StudyStore again(recorder, config, plan);  // the file's plan is the record's beginning
    CHECK(again.Plan().size() == 20);
  }
  SECTION("a study planned differently is refused, saying what differs") {
    StudyConfig changed = config;
    changed.order = StudyOrder::kFixed;
    CHECK_THROWS_WITH(StudyStore(recorder, changed, PlanTrials(changed)),
                      Catch::Contains("planned differently") && Catch::Contains("another name"));
    StudyConfig more = FourConditions(dir, 8);
    CHECK_THROWS_WITH(StudyStore(recorder, more, PlanTrials(more)), Catch::Contains("16 trials on record, 32"));
  }
}
