// A questionnaire submitted by the console: refused when it is out of order,
// answered already, or incomplete — with a message and no second row — and
// stored with its score when it is right.
#include <catch2/catch.hpp>

#include "haptel/config/paths.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/submission.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

size_t Rows(const StudyStore& store) { return store.Answers().size(); }

}  // namespace

TEST_CASE("Submitted questionnaires are checked, ordered, never doubled, and scored") {
  const auto dir = test::ScratchDir("study-submission");
  StudyConfig config;
  config.file = dir / "s.yaml";
  test::WriteFile(config.file, "name: s\n");
  config.name = "s";
  config.conditions = {{"cockpit", "cockpit"}, {"gesture", "gesture"}};
  config.participants = {{"A", ""}, {"B", ""}};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1},
                                          {"A", 2, "cockpit", 1},
                                          {"B", 1, "cockpit", 1},
                                          {"B", 2, "gesture", 1}};
  record::Recorder recorder(dir / "s.db");
  StudyStore store(recorder, config, plan);
  recorder.Save(test::TrialRun(20.0),
                store.TrialWriter(plan[0], 600.0));  // A has driven gesture, nothing else
  const std::filesystem::path shipped = ShippedFile("config/questionnaires");
  const std::map<std::string, Questionnaire> questionnaires = {
      {"thesis", FindQuestionnaire(shipped, "thesis")},
      {"rating", FindQuestionnaire(shipped, "rating")}};
  const std::map<std::string, std::string> thesis = {
      {"easy_to_learn", "4"}, {"efficient", "5"}, {"remarks", "  the wall stopped my hand  "}};

  SECTION("out of order: before the participant drove the condition") {
    const SubmissionResult r =
        SubmitAnswers(store, questionnaires, "A", "cockpit", "thesis", thesis);
    CHECK_FALSE(r.accepted);
    CHECK(r.status == 409);
    CHECK(r.message.find("has not finished condition cockpit") != std::string::npos);
    CHECK(Rows(store) == 0);
  }
  SECTION("a missing answer: refused, naming the item, nothing stored") {
    auto missing = thesis;
    missing.erase("efficient");
    const SubmissionResult r =
        SubmitAnswers(store, questionnaires, "A", "gesture", "thesis", missing);
    CHECK_FALSE(r.accepted);
    CHECK(r.status == 422);
    REQUIRE(r.errors.size() == 1);
    CHECK(r.errors[0].item == "efficient");
    CHECK(Rows(store) == 0);
  }
  SECTION("accepted once; the same form again is refused and keeps one set of rows") {
    const SubmissionResult first =
        SubmitAnswers(store, questionnaires, "A", "gesture", "thesis", thesis);
    CHECK(first.accepted);
    CHECK(first.status == 200);
    const std::vector<AnswerRow> rows = store.Answers();
    REQUIRE(rows.size() == 3);  // no score: the thesis's questions have none
    CHECK(rows[2].item == "remarks");
    CHECK(rows[2].value == "the wall stopped my hand");
    const SubmissionResult again =
        SubmitAnswers(store, questionnaires, "A", "gesture", "thesis", thesis);
    CHECK_FALSE(again.accepted);
    CHECK(again.status == 409);
    CHECK(again.message.find("already answered") != std::string::npos);
    CHECK(Rows(store) == 3);
  }
  SECTION("the rating tree: its path and rating, and the rating as the score") {
    // A rating outside the band the path reached (4..6) is refused first.
    const SubmissionResult outside = SubmitAnswers(
        store, questionnaires, "A", "gesture", "rating",
        {{"rating", "2"}, {"rating.path", "controllable=yes,adequate=yes,satisfactory=no"}});
    CHECK(outside.status == 422);
    CHECK(Rows(store) == 0);
    const SubmissionResult r = SubmitAnswers(
        store, questionnaires, "A", "gesture", "rating",
        {{"rating", "5"}, {"rating.path", "controllable=yes,adequate=yes,satisfactory=no"}});
    REQUIRE(r.accepted);
    const std::vector<AnswerRow> rows = store.Answers();
    REQUIRE(rows.size() == 3);
    CHECK(rows.back().item == "score");
    CHECK(rows.back().value == "5");
  }
  SECTION("unknown questionnaire, participant or condition: 400") {
    CHECK(SubmitAnswers(store, questionnaires, "A", "gesture", "sus", thesis).status == 400);
    CHECK(SubmitAnswers(store, questionnaires, "Z", "gesture", "thesis", thesis).status == 400);
    CHECK(SubmitAnswers(store, questionnaires, "A", "keyboard", "thesis", thesis).status == 400);
    CHECK(Rows(store) == 0);
  }
}
