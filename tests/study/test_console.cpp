// The experimenter's console through real HTTP on 127.0.0.1: the schedule,
// a questionnaire's form, submissions (accepted once; refused twice, out of
// order or incomplete, with a status and a message), and a port in use.
// clang-format off
// Before httplib.h: it brings <resolv.h>, whose `_res` macro breaks Eigen's
// headers (which study_sessions.hpp brings through the run configuration).
#include "haptel/study/study_sessions.hpp"
#include <httplib.h>
// clang-format on

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <iterator>
#include <memory>
#include <thread>

#include "console_client.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/core/json.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/console.hpp"
#include "haptel/study/report.hpp"
#include "haptel/study/submission.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

/// A study file of the test's own in `dir`, named `name`-study.
StudyConfig SmallStudy(const std::filesystem::path& dir, const std::string& name,
                       const std::string& operators, std::vector<StudyCondition> conditions) {
  StudyConfig config;
  config.file = dir / (name + ".yaml");
  test::WriteFile(config.file, "name: " + name + "\n");
  config.name = name + "-study";
  config.operators = operators;
  config.conditions = std::move(conditions);
  return config;
}

std::string ReadText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
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
      {"thesis", FindQuestionnaire(shipped, "thesis")},
      {"rating", FindQuestionnaire(shipped, "rating")}};
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
  CHECK(schedule->body.find("screen-line") == std::string::npos);  // nothing said yet
  // The participant's screen's line, for the experimenter (page and status).
  console.SetLiveProgress({3.2, 0, 2, 0, "", "Not engaged - bring the hand back to neutral"});
  const auto live = client.Get("/");
  REQUIRE(live);
  CHECK(live->body.find("their screen: Not engaged - bring the hand back to neutral") !=
        std::string::npos);
  const auto status = client.Get("/status.json");
  REQUIRE(status);
  CHECK(status->body.find("\"live_message\":\"Not engaged - bring the hand back to neutral\"") !=
        std::string::npos);
  CHECK(schedule->body.find("/questionnaire?participant=A&amp;condition=gesture&amp;name=thesis") !=
        std::string::npos);

  const auto form = client.Get("/questionnaire?participant=A&condition=gesture&name=thesis");
  REQUIRE(form);
  CHECK(form->status == 200);
  CHECK(form->body.find("name=\"easy_to_learn\" value=\"5\"") != std::string::npos);
  CHECK(form->body.find("<textarea name=\"remarks\"") != std::string::npos);

  const httplib::Params good = {{"participant", "A"},        {"condition", "gesture"},
                                {"questionnaire", "thesis"}, {"easy_to_learn", "4"},
                                {"efficient", "5"},          {"remarks", "fine"}};
  const auto first = client.Post("/answers", good);
  REQUIRE(first);
  CHECK(first->status == 200);
  const auto twice = client.Post("/answers", good);
  REQUIRE(twice);
  CHECK(twice->status == 409);
  CHECK(twice->body.find("already answered") != std::string::npos);

  const auto incomplete = client.Post("/answers", httplib::Params{{"participant", "A"},
                                                                  {"condition", "gesture"},
                                                                  {"questionnaire", "rating"},
                                                                  {"rating", "5"}});
  REQUIRE(incomplete);
  CHECK(incomplete->status == 422);
  const auto early = client.Post("/answers", httplib::Params{{"participant", "A"},
                                                             {"condition", "cockpit"},
                                                             {"questionnaire", "thesis"},
                                                             {"easy_to_learn", "4"},
                                                             {"efficient", "5"}});
  REQUIRE(early);
  CHECK(early->status == 409);
  CHECK(early->body.find("has not finished condition cockpit") != std::string::npos);

  // The rating tree as the form sends it: a yes/no per question, then the rating.
  const auto rating = client.Post("/answers", httplib::Params{{"participant", "A"},
                                                              {"condition", "gesture"},
                                                              {"questionnaire", "rating"},
                                                              {"rating.node.controllable", "yes"},
                                                              {"rating.node.adequate", "yes"},
                                                              {"rating.node.satisfactory", "no"},
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
  CHECK_THROWS_WITH(
      StudyConsole(config, plan, db, questionnaires, taken),
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
  StudyConfig config =
      SmallStudy(dir, "open", "person", {{"cockpit", "cockpit"}, {"gesture", "gesture"}});
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
  CHECK(page->body.find(
            "1 participant; the balanced Latin square is balanced over blocks of 2: add 1 more") !=
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
  for (const PlannedTrial& t : plan)
    recorder.Save(test::TrialRun(30.0), store.TrialWriter(t, 600.0));
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

TEST_CASE("The Finish that ends an open study is answered before the console stops") {
  // The study ends as soon as Finish is taken, and the console's end cut
  // every open socket: the Finish's own 303 could be cut before it was
  // written (a person study's e2e case saw no answer under load).
  const auto dir = test::ScratchDir("study-console-finish");
  StudyConfig config = SmallStudy(dir, "finish", "person", {{"cockpit", "cockpit"}});
  int answered = 0;
  constexpr int kRounds = 25;
  for (int round = 0; round < kRounds; ++round) {
    ConsoleOptions options;
    options.port = 0;
    auto console = std::make_unique<StudyConsole>(config, std::vector<PlannedTrial>{},
                                                  dir / ("finish-" + std::to_string(round) + ".db"),
                                                  std::map<std::string, Questionnaire>{}, options);
    test::ConsoleClient client("127.0.0.1", console->port());
    REQUIRE_FALSE(client.token().empty());
    int finish_status = 0;  // 0: no answer
    std::atomic<bool> stop{false};
    std::thread press([&] {
      // Finish is refused (409) until the study waits for more.
      for (int i = 0; i < 500; ++i) {
        const auto finish = client.Post("/finish");
        finish_status = finish ? finish->status : 0;
        if (finish_status != 409) return;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      stop.store(true);
    });
    CHECK_FALSE(console->WaitForMore(stop));
    console.reset();  // at once, as the study's end does
    press.join();
    answered += finish_status == 303 ? 1 : 0;
  }
  CHECK(answered == kRounds);
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
  // Frames counted before one decodes hand over no picture: the page keeps
  // the last one and its count, never a count with nothing to show (an
  // e2e study read 404 after seeing frames).
  console.SetPicture({}, 25);
  const auto kept = client.Get("/video.jpg");
  REQUIRE(kept);
  CHECK(kept->status == 200);
  CHECK(std::vector<uint8_t>(kept->body.begin(), kept->body.end()) == jpeg);
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

TEST_CASE(
    "The experimenter's notes: on a trial or the one under way, stored, exported escaped, refused "
    "with a reason") {
  const auto dir = test::ScratchDir("study-console-notes");
  StudyConfig config =
      SmallStudy(dir, "notes", "person", {{"cockpit", "cockpit"}, {"gesture", "gesture"}});
  config.participants = {{"A", ""}};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  const auto db = dir / "notes.db";
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, db, {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());

  // Every row of the schedule has a note form; the trial under way has its own.
  console.SetLive("trial 1 of 2: participant A, gesture (position 1)", "A", 1);
  const auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->body.find("action=\"/notes\"") != std::string::npos);
  CHECK(page->body.find("id=\"live-note\"") != std::string::npos);

  const auto noted = client.Post("/notes", {{"participant", "A"},
                                            {"position", "1"},
                                            {"text", "  looked at the hands, not the screen  "}});
  REQUIRE(noted);
  CHECK(noted->status == 303);
  // A remark a spreadsheet would run as a formula, on the participant as a whole.
  CHECK(
      client
          .Post("/notes", {{"participant", "A"}, {"position", "0"}, {"text", "=HYPERLINK(\"x\")"}})
          ->status == 303);
  // Characters, not bytes: 2000 CJK characters (6000 bytes, 18000 url-encoded) fit; 2001 do not.
  std::string cjk;
  for (int i = 0; i < kMaxNoteCharacters; ++i) cjk += "\xE6\xBC\xA2";
  CHECK(client.Post("/notes", {{"participant", "A"}, {"position", "2"}, {"text", cjk}})->status ==
        303);
  const auto long_note =
      client.Post("/notes", {{"participant", "A"}, {"position", "2"}, {"text", cjk + "x"}});
  REQUIRE(long_note);
  CHECK(long_note->status == 422);
  CHECK(long_note->body.find("at most 2000 characters, this one has 2001") != std::string::npos);
  const auto empty =
      client.Post("/notes", {{"participant", "A"}, {"position", "1"}, {"text", "  "}});
  REQUIRE(empty);
  CHECK(empty->status == 422);
  CHECK(empty->body.find("the note is empty") != std::string::npos);
  const auto nowhere =
      client.Post("/notes", {{"participant", "A"}, {"position", "7"}, {"text", "x"}});
  REQUIRE(nowhere);
  CHECK(nowhere->status == 400);
  CHECK(nowhere->body.find("no trial at position &#39;7&#39;") != std::string::npos);
  CHECK(client.Post("/notes", {{"participant", "Z"}, {"position", "1"}, {"text", "x"}})->status ==
        400);
  // Another site's form, or one without the console's token: refused, nothing stored.
  const httplib::Params forged = {
      {"participant", "A"}, {"position", "1"}, {"text", "forged"}, {"csrf", client.token()}};
  const auto cross = client.raw().Post("/notes", {{"Origin", "http://evil.example"}}, forged);
  REQUIRE(cross);
  CHECK(cross->status == 403);
  const auto tokenless = client.raw().Post(
      "/notes", httplib::Params{{"participant", "A"}, {"position", "1"}, {"text", "forged"}});
  REQUIRE(tokenless);
  CHECK(tokenless->status == 403);

  // Shown on the schedule, escaped.
  const auto shown = client.Get("/");
  REQUIRE(shown);
  CHECK(shown->body.find("looked at the hands, not the screen") != std::string::npos);
  CHECK(shown->body.find("=HYPERLINK(&quot;x&quot;)") != std::string::npos);

  // Stored as written (trimmed), in order.
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    const std::vector<NoteRow> notes = store.Notes();
    REQUIRE(notes.size() == 3);
    CHECK(notes[0].participant == "A");
    CHECK(notes[0].position == 1);
    CHECK(notes[0].text == "looked at the hands, not the screen");
    CHECK(notes[1].position == 0);
    CHECK(notes[2].text == cjk);
    CHECK_FALSE(notes[0].noted_utc.empty());
  }
  // In the report: its text, its page and notes.csv, the formula kept as text.
  const StudyResults results = LoadStudyResults(db, config.name);
  REQUIRE(results.notes.size() == 3);
  CHECK(results.notes[0].condition == "gesture");
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  CHECK(FormatReport(results, report).find("A, gesture (position 1): looked at the hands") !=
        std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "report");
  const std::string csv = ReadText(files.notes_csv);
  CHECK(csv.rfind("study,participant,position,condition,noted_utc,text\n", 0) == 0);
  CHECK(csv.find(",gesture,") != std::string::npos);
  CHECK(csv.find("\"'=HYPERLINK(\"\"x\"\")\"") != std::string::npos);
  CHECK(csv.find(",=HYPERLINK") == std::string::npos);
  CHECK(ReadText(files.html).find("looked at the hands, not the screen") != std::string::npos);
}

TEST_CASE(
    "The participants' background: asked once before the first trial, stored with no condition, "
    "exported") {
  const auto dir = test::ScratchDir("study-console-demographics");
  StudyConfig config =
      SmallStudy(dir, "background", "person", {{"cockpit", "cockpit"}, {"gesture", "gesture"}});
  config.participants = {{"A", ""}, {"B", ""}};
  config.questionnaires = {"thesis"};
  config.demographics = "demographics";
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1},
                                          {"A", 2, "cockpit", 1},
                                          {"B", 1, "cockpit", 1},
                                          {"B", 2, "gesture", 1}};
  const auto db = dir / "background.db";
  const std::filesystem::path shipped = ShippedFile("config/questionnaires");
  const std::map<std::string, Questionnaire> questionnaires = {
      {"thesis", FindQuestionnaire(shipped, "thesis")},
      {"demographics", FindQuestionnaire(shipped, "demographics")}};
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, db, questionnaires, options);
  test::ConsoleClient client("127.0.0.1", console.port());

  // Before any trial: each participant's first row links to the form.
  const auto schedule = client.Get("/");
  REQUIRE(schedule);
  CHECK(schedule->body.find("/questionnaire?participant=A&amp;condition=&amp;name=demographics") !=
        std::string::npos);
  CHECK(schedule->body.find("/questionnaire?participant=B&amp;condition=&amp;name=demographics") !=
        std::string::npos);
  const auto form = client.Get("/questionnaire?participant=A&condition=&name=demographics");
  REQUIRE(form);
  CHECK(form->body.find("before their first trial") != std::string::npos);
  CHECK(form->body.find("value=\"prefer-not-to-say\"") != std::string::npos);

  httplib::Params answers = {{"participant", "A"},
                             {"condition", ""},
                             {"questionnaire", "demographics"},
                             {"age_band", "25-34"},
                             {"gender", "self-described"},
                             {"gender_description", "=agender"},
                             {"handedness", "left"},
                             {"video_games", "weekly"},
                             {"driving", "no-licence"},
                             {"haptic_devices", "never"}};
  const auto first = client.Post("/answers", answers);
  REQUIRE(first);
  CHECK(first->status == 200);
  const auto twice = client.Post("/answers", answers);
  REQUIRE(twice);
  CHECK(twice->status == 409);
  CHECK(twice->body.find("already answered") != std::string::npos);
  // About no condition: not after one, and no other questionnaire without one.
  answers.erase("condition");
  answers.emplace("condition", "gesture");
  const auto after = client.Post("/answers", answers);
  REQUIRE(after);
  CHECK(after->status == 400);
  CHECK(after->body.find("before their first trial") != std::string::npos);
  const auto thesis = client.Post("/answers", {{"participant", "B"},
                                               {"condition", ""},
                                               {"questionnaire", "thesis"},
                                               {"easy_to_learn", "4"},
                                               {"efficient", "4"}});
  REQUIRE(thesis);
  CHECK(thesis->status == 400);
  // A missing choice is refused like any questionnaire's.
  const auto incomplete = client.Post("/answers", {{"participant", "B"},
                                                   {"condition", ""},
                                                   {"questionnaire", "demographics"},
                                                   {"age_band", "18-24"}});
  REQUIRE(incomplete);
  CHECK(incomplete->status == 422);
  CHECK(client
            .Post("/answers", {{"participant", "B"},
                               {"condition", ""},
                               {"questionnaire", "demographics"},
                               {"age_band", "18-24"},
                               {"gender", "prefer-not-to-say"},
                               {"handedness", "right"},
                               {"video_games", "never"},
                               {"driving", "daily"},
                               {"haptic_devices", "regularly"}})
            ->status == 200);
  const auto done = client.Get("/");
  REQUIRE(done);
  CHECK(done->body.find("name=demographics") == std::string::npos);  // answered: no link left

  // Stored with the answers, condition empty; exported one row per participant.
  const StudyResults results = LoadStudyResults(db, config.name);
  int background = 0;
  for (const StudyResults::Answer& a : results.answers) {
    CHECK(a.condition.empty());
    background += a.questionnaire == "demographics" ? 1 : 0;
  }
  CHECK(background == 13);  // A: 7 items; B: 6 (no description)
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  CHECK(FormatReport(results, report).find("demographics.age_band: 25-34 1, 18-24 1") !=
        std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "report");
  const std::string csv = ReadText(files.demographics_csv);
  CHECK(csv.rfind(
            "study,participant,age_band,gender,gender_description,handedness,video_games,driving,"
            "haptic_devices\n",
            0) == 0);
  CHECK(
      csv.find(
          "background-study,A,25-34,self-described,\"'=agender\",left,weekly,no-licence,never\n") !=
      std::string::npos);
  CHECK(csv.find("background-study,B,18-24,prefer-not-to-say,,right,never,daily,regularly\n") !=
        std::string::npos);
  CHECK(ReadText(files.answers_csv).find("background-study,A,,demographics,age_band,25-34") !=
        std::string::npos);
  // Not a remark about an interface.
  CHECK(ReadText(files.html).find("<h2>Remarks</h2>") == std::string::npos);
}

TEST_CASE(
    "A flagged trial is marked on the schedule with its flags; its redo keeps it as superseded") {
  const auto dir = test::ScratchDir("study-console-flagged");
  StudyConfig config =
      SmallStudy(dir, "flagged", "person", {{"cockpit", "cockpit"}, {"gesture", "gesture"}});
  config.participants = {{"A", ""}};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1}, {"A", 2, "cockpit", 1}};
  const auto db = dir / "flagged.db";
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    record::RunRecord spoiled = test::TrialRun(25.0);
    spoiled.physics_rate_short = true;
    recorder.Save(spoiled, store.TrialWriter(plan[0], 600.0));
    recorder.Save(test::TrialRun(30.0), store.TrialWriter(plan[1], 600.0));
  }
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, db, {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());
  const auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->body.find("class=\"done flagged\"") != std::string::npos);
  CHECK(page->body.find("! physics rate short") != std::string::npos);
  CHECK(page->body.find("action=\"/redo\"") != std::string::npos);

  CHECK(client.Post("/redo", {{"participant", "A"}, {"position", "1"}})->status == 303);
  {
    record::Recorder recorder(db);
    StudyStore store(recorder, config, plan);
    REQUIRE(store.Superseded().size() == 1);
    CHECK(store.Superseded()[0].trial.flags == "physics rate short");
    recorder.Save(test::TrialRun(22.0), store.TrialWriter(plan[0], 600.0));  // run again, clean
  }
  const auto again = client.Get("/");
  REQUIRE(again);
  CHECK(again->body.find("class=\"done flagged\"") == std::string::npos);
  CHECK(again->body.find("(attempt 2)") != std::string::npos);
  // The report counts the latest attempt only, and lists the superseded one.
  const StudyResults results = LoadStudyResults(db, config.name);
  REQUIRE(results.trials.size() == 2);
  REQUIRE(results.superseded.size() == 1);
  CHECK(results.superseded[0].trial.lap_time_s == 25.0);
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  CHECK(report.conditions[1].total_lap_time_s == 22.0);  // gesture: the second attempt
  const std::string text = FormatReport(results, report);
  CHECK(text.find("superseded trials (run again; only the latest attempt is counted)") !=
        std::string::npos);
  CHECK(text.find("A, gesture (position 1, attempt 1, run 1): 25.00 s; from the console") !=
        std::string::npos);
}

TEST_CASE(
    "The console names each trial's device, and refuses to start one whose device is not there") {
  const auto dir = test::ScratchDir("study-console-device");
  StudyConfig config = SmallStudy(dir, "device", "person",
                                  {{"cockpit", "cockpit", false, dir / "wheel.yaml", "wheel"},
                                   {"gesture", "gesture", false, dir / "mouse.yaml", "mouse"}});
  config.participants = {{"A", ""}};
  const std::vector<PlannedTrial> plan = {{"A", 1, "gesture", 1, "mouse"},
                                          {"A", 2, "cockpit", 1, "wheel"}};
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, plan, dir / "s.db", {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());
  // The trial's device as its driver would answer: missing, then plugged in.
  std::atomic<bool> plugged{false};
  const TrialDevice mouse{"mouse", dir / "mouse.yaml", [&plugged] {
                            return plugged.load() ? std::string()
                                                  : std::string("no display (DISPLAY is not set)");
                          }};
  std::atomic<bool> stop{false};
  std::atomic<bool> started{false};
  std::thread study([&] {
    started.store(console.WaitForStart("participant A, gesture (position 1)", stop, mouse));
  });
  auto status = [&](const std::string& key) {
    const auto r = client.Get("/status.json");
    return r ? JsonFieldOf(r->body, key) : std::string();
  };
  REQUIRE(test::WaitFor([&] { return !status("next").empty(); }, 20.0));
  CHECK(status("next_device") == "mouse");
  CHECK(status("device_missing") == "no display (DISPLAY is not set)");
  // The schedule: each planned trial's device, and the offered one's, with what it lacks.
  const auto page = client.Get("/");
  REQUIRE(page);
  CHECK(page->body.find("<th>device</th>") != std::string::npos);
  CHECK(page->body.find("<td>wheel</td>") != std::string::npos);
  CHECK(page->body.find("id=\"next-device\">Device: <b>mouse</b>") != std::string::npos);
  CHECK(page->body.find("id=\"device-missing\"") != std::string::npos);
  CHECK(page->body.find("no display (DISPLAY is not set)") != std::string::npos);
  // Start is refused while it is missing, saying so; the trial still waits.
  const auto refused = client.Post("/start");
  REQUIRE(refused);
  CHECK(refused->status == 409);
  CHECK(refused->body.find("device mouse") != std::string::npos);
  CHECK(refused->body.find("no display (DISPLAY is not set)") != std::string::npos);
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  CHECK_FALSE(started.load());
  CHECK_FALSE(status("next").empty());
  // Plugged in: no longer said, and Start starts it.
  plugged.store(true);
  CHECK(status("device_missing").empty());
  const auto page_now = client.Get("/");
  REQUIRE(page_now);
  CHECK(page_now->body.find("id=\"device-missing\"") == std::string::npos);
  const auto start = client.Post("/start");
  REQUIRE(start);
  CHECK(start->status == 303);
  study.join();
  CHECK(started.load());
  CHECK(status("next_device").empty());
}

TEST_CASE(
    "A study's force-feedback joystick that is not plugged in: its trial is offered with the "
    "device's line, and Start is refused saying so") {
  const auto dir = test::ScratchDir("study-console-ff-missing");
  // grand-prix-ff.yaml's gesture condition on the shipped joystick file, its
  // SDL index one that no machine has (the shipped file takes the first there
  // is): the driver's own check, as the study asks it, says it is missing.
  StudyConfig config = LoadStudy("config/studies/grand-prix-ff.yaml");
  StudyCondition gesture;
  for (const StudyCondition& c : config.conditions)
    if (c.name == "gesture") gesture = c;
  REQUIRE(gesture.device_name == "sdl-ff");
  std::string stick = ReadText(gesture.device);
  const size_t index = stick.find("joystick: -1");
  REQUIRE(index != std::string::npos);
  stick.replace(index, std::string("joystick: -1").size(), "joystick: 31");
  gesture.device = test::WriteFile(dir / "sdl-ff.yaml", stick);
  const TrialDevice device = DeviceOf(gesture);
  const std::string missing = device.unavailable();
  CHECK_THAT(missing, Catch::Contains("joystick"));  // none connected, or not number 31

  config.participants = {{"A", ""}};
  ConsoleOptions options;
  options.port = 0;
  StudyConsole console(config, {{"A", 1, "gesture", 1, "sdl-ff"}}, dir / "s.db", {}, options);
  test::ConsoleClient client("127.0.0.1", console.port());
  std::atomic<bool> stop{false};
  std::atomic<bool> started{false};
  std::thread study([&] {
    started.store(console.WaitForStart("participant A, gesture (position 1)", stop, device));
  });
  auto status = [&](const std::string& key) {
    const auto r = client.Get("/status.json");
    return r ? JsonFieldOf(r->body, key) : std::string();
  };
  REQUIRE(test::WaitFor([&] { return !status("next").empty(); }, 20.0));
  CHECK(status("next_device") == "sdl-ff");
  CHECK(status("device_missing") == missing);
  const auto refused = client.Post("/start");
  REQUIRE(refused);
  CHECK(refused->status == 409);
  CHECK(refused->body.find("device sdl-ff") != std::string::npos);
  CHECK(refused->body.find((dir / "sdl-ff.yaml").string()) != std::string::npos);
  CHECK(refused->body.find("joystick") != std::string::npos);
  stop.store(true);
  study.join();
  CHECK_FALSE(started.load());
}
