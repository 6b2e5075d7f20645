// The experimenter's console through real HTTP on 127.0.0.1: the schedule,
// a questionnaire's form, submissions (accepted once; refused twice, out of
// order or incomplete, with a status and a message), and a port in use.
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <thread>

#include <catch2/catch.hpp>

#include "haptel/config/paths.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/console.hpp"
#include "console_client.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// A study file of the test's own in `dir`, named `name`-study.
StudyConfig SmallStudy(const std::filesystem::path& dir, const std::string& name, const std::string& operators,
                       std::vector<StudyCondition> conditions) {
  StudyConfig config;
  config.file = dir / (name + ".yaml");
  test::WriteFile(config.file, "name: " + name + "\n");
  config.name = name + "-study";
  config.operators = operators;
  config.conditions = std::move(conditions);
  return config;
}

}  // namespace

TEST_CASE("The console serves the schedule and forms, and takes each questionnaire once") {
  const auto dir = test::ScratchDir("study-console");
  StudyConfig config;
  config.file = dir / "s.yaml";
  test::WriteFile(config.file, "name: s\n");
  config.name = "console-study";
  config.conditions = {{"cockpit", "cockpit"}, {"gesture", "gesture"}};
  config.participants = {{"A", ""}};
  config.questionnaires = {"thesis", "rating"};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  const auto db = dir / "s.db";
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    recorder.Save(test::TrialRun(21.5), store.TrialWriter(plan[0], 600.0));  // A drove gesture
  }
  const std::filesystem::path shipped = ShippedFile("config/questionnaires");
  const std::map<std::string, Questionnaire> questionnaires = {
      {"thesis", FindQuestionnaire(shipped, "thesis")}, {"rating", FindQuestionnaire(shipped, "rating")}};
  ConsoleOptions options;
  options.port = 0;  // any free port
  StudyConsole console(config, plan, db, questionnaires, options);
  console.SetLive("participant A, cockpit: lap 3.2 s");
  test::ConsoleClient client("127.0.0.1", console.port());

  const auto schedule = client.Get("/");
  REQUIRE(schedule);
  CHECK(schedule->status == 200);
  CHECK(schedule->body.find("1 of 2 trials done") != std::string::npos);
  CHECK(schedule->body.find("21.50 s") != std::string::npos);
  CHECK(schedule->body.find("participant A, cockpit: lap 3.2 s") != std::string::npos);
  CHECK(schedule->body.find("/questionnaire?participant=A&amp;condition=gesture&amp;name=thesis") != std::string::npos);

  const auto form = client.Get("/questionnaire?participant=A&condition=gesture&name=thesis");
  REQUIRE(form);
  CHECK(form->status == 200);
  CHECK(form->body.find("name=\"easy_to_learn\" value=\"5\"") != std::string::npos);
  CHECK(form->body.find("<textarea name=\"remarks\"") != std::string::npos);

  const httplib::Params good = {{"participant", "A"}, {"condition", "gesture"}, {"questionnaire", "thesis"},
                                {"easy_to_learn", "4"}, {"efficient", "5"}, {"remarks", "fine"}};
  const auto first = client.Post("/answers", good);
  REQUIRE(first);
  CHECK(first->status == 200);
  const auto twice = client.Post("/answers", good);
  REQUIRE(twice);
  CHECK(twice->status == 409);
  CHECK(twice->body.find("already answered") != std::string::npos);

  const auto incomplete = client.Post("/answers", httplib::Params{{"participant", "A"}, {"condition", "gesture"},
                                                   {"questionnaire", "rating"}, {"rating", "5"}});
  REQUIRE(incomplete);
  CHECK(incomplete->status == 422);
  const auto early = client.Post("/answers", httplib::Params{{"participant", "A"}, {"condition", "cockpit"},
                                              {"questionnaire", "thesis"}, {"easy_to_learn", "4"},
                                              {"efficient", "5"}});
  REQUIRE(early);
  CHECK(early->status == 409);
  CHECK(early->body.find("has not finished condition cockpit") != std::string::npos);

  // The rating tree as the form sends it: a yes/no per question, then the rating.
  const auto rating = client.Post("/answers", httplib::Params{{"participant", "A"}, {"condition", "gesture"},
                                               {"questionnaire", "rating"}, {"rating.node.controllable", "yes"},
                                               {"rating.node.adequate", "yes"}, {"rating.node.satisfactory", "no"},
                                               {"rating", "5"}});
  REQUIRE(rating);
  CHECK(rating->status == 200);

  // What is stored: one set of thesis answers, the rating with its path and score.
  record::Recorder recorder(db);
  StudyStore store(recorder, config, plan);
  std::map<std::string, std::string> stored;
  for (const AnswerRow& a : store.Answers()) stored[a.questionnaire + "." + a.item] = a.value;
  CHECK(store.Answers().size() == 6);
  CHECK(stored["thesis.easy_to_learn"] == "4");
  CHECK(stored["rating.rating"] == "5");
  CHECK(stored["rating.rating.path"] == "controllable=yes,adequate=yes,satisfactory=no");
  CHECK(stored["rating.score"] == "5");

  // Redo: the finished trial is taken back (its run stays), once; run again it is attempt 2.
  const auto redo = client.Post("/redo", httplib::Params{{"participant", "A"}, {"position", "1"}});
  REQUIRE(redo);
  CHECK(redo->status == 303);
  const auto again = client.Post("/redo", httplib::Params{{"participant", "A"}, {"position", "1"}});
  REQUIRE(again);
  CHECK(again->status == 409);
  CHECK(store.Trials().empty());
  CHECK(store.NextTrial()->position == 1);
  recorder.Save(test::TrialRun(19.0), store.TrialWriter(plan[0], 600.0));
  REQUIRE(store.Trials().size() == 1);
  CHECK(store.Trials()[0].attempt == 2);
  CHECK(store.Trials()[0].lap_time_s == 19.0);
  CHECK(recorder.LoadAll().size() == 2);  // the first run is kept

  // A second console on the same port: a clear error naming it.
  ConsoleOptions taken;
  taken.port = console.port();
  CHECK_THROWS_WITH(StudyConsole(config, plan, db, questionnaires, taken),
                    Catch::Contains("127.0.0.1:" + std::to_string(console.port())) && Catch::Contains("in use"));
  // ... refused before it wrote anything: a study whose console cannot
  // listen has no plan in its database (it was written first, and then refused).
  const auto untouched = dir / "untouched.db";
  CHECK_THROWS_AS(StudyConsole(config, plan, untouched, questionnaires, taken), ConsoleError);
  record::Recorder fresh(untouched);
  CHECK(StudyStore(fresh, config, {}).Plan().empty());
}

TEST_CASE("The console adds participants to an open study, each once, and finishes it on request") {
  const auto dir = test::ScratchDir("study-console-open");
  StudyConfig config = SmallStudy(dir, "open", "person", {{"cockpit", "cockpit"}, {"gesture", "gesture"}});
  const auto db = dir / "open.db";
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, {}, db, {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());

  const auto added = client.Post("/participants", httplib::Params{{"id", "P1"}});
  REQUIRE(added);
  CHECK(added->status == 303);
  const auto twice = client.Post("/participants", httplib::Params{{"id", "P1"}});
  REQUIRE(twice);
  CHECK(twice->status == 409);
  CHECK(twice->body.find("P1 is in the study already") != std::string::npos);
  const auto bad = client.Post("/participants", httplib::Params{{"id", "P 2<"}});
  REQUIRE(bad);
  CHECK(bad->status == 422);
  CHECK(bad->body.find("1 to 40 letters") != std::string::npos);
  const auto page = client.Get("/");
  REQUIRE(page);
  // Two conditions: Williams' square has two rows, so a block is two people.
  CHECK(page->body.find("1 participant; the balanced Latin square is balanced over blocks of 2: add 1 more") !=
        std::string::npos);
  CHECK(client.Post("/participants", httplib::Params{{"id", "P2"}})->status == 303);

  record::Recorder recorder(db);
  StudyStore store(recorder, config, {});
  const std::vector<PlannedTrial> plan = store.Plan();
  REQUIRE(plan.size() == 4);
  CHECK(plan[0].participant == "P1");
  CHECK(plan[0].condition == "cockpit");
  CHECK(plan[2].participant == "P2");
  CHECK(plan[2].condition == "gesture");  // the square's second row

  // Finish only while nothing is left to run.
  CHECK(client.Post("/finish")->status == 409);
  for (const PlannedTrial& t : plan) recorder.Save(test::TrialRun(30.0), store.TrialWriter(t, 600.0));
  std::atomic<bool> stop{false};
  std::thread press([&] {
    for (int i = 0; i < 500; ++i) {
      const auto r = client.Post("/finish");
      if (r && r->status == 303) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    stop.store(true);  // never accepted: end the wait, fail below
  });
  const bool more = console.WaitForMore(stop);
  press.join();
  CHECK_FALSE(more);
  CHECK_FALSE(stop.load());

  // No camera configured: no thumbnail, and the picture's address says so.
  const auto picture = client.Get("/video.jpg");
  REQUIRE(picture);
  CHECK(picture->status == 404);
  CHECK(console.video_frames() == 0);
}

TEST_CASE("the thumbnail is the picture the trial's session hands over, as it came") {
  const auto dir = test::ScratchDir("study-console-thumbnail");
  StudyConfig config = SmallStudy(dir, "thumb", "person", {{"cockpit", "cockpit"}});
  ConsoleOptions options;
  options.port = 0;
  options.thumbnail = true;
  StudyConsole console(config, {}, dir / "thumb.db", {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());
  // Before any picture: nothing to show yet.
  const auto none = client.Get("/video.jpg");
  REQUIRE(none);
  CHECK(none->status == 404);
  const std::vector<uint8_t> jpeg{0xFF, 0xD8, 0xFF, 0xE0, 1, 2, 3, 0xFF, 0xD9};
  console.SetPicture(jpeg, 17);
  const auto picture = client.Get("/video.jpg");
  REQUIRE(picture);
  CHECK(picture->status == 200);
  CHECK(picture->get_header_value("Content-Type") == "image/jpeg");
  CHECK(std::vector<uint8_t>(picture->body.begin(), picture->body.end()) == jpeg);
  CHECK(console.video_frames() == 17);
}

TEST_CASE("Simulated drivers come from the study file, not the console") {
  const auto dir = test::ScratchDir("study-console-synthetic");
  StudyConfig config = SmallStudy(dir, "syn", "synthetic", {{"gesture", "gesture"}});
  config.participants = {{"A", "p"}};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}};
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, dir / "syn.db", {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());
  const auto added = client.Post("/participants", httplib::Params{{"id", "B"}});
  REQUIRE(added);
  CHECK(added->status == 409);
  CHECK(added->body.find("study file") != std::string::npos);
}
