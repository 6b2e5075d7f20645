// The study's tables (StudyStore) on a real SQLite file, and the plan of a
// participant added later (PlanParticipant): what a kill between any two
// transactions leaves, a changed study refused naming each changed key and
// both values (a study planned before definitions were kept: once its plan
// matches, held to its file from then on), trials and answers never twice,
// participants added in the console after the file's.
#include <sqlite3.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "haptel/mediator/session.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/definition.hpp"
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
  // The cockpits on a wheel, the gesture with the mouse (devices by name:
  // the store keeps the name, the definition the file).
  config.conditions = {{"a", "cockpit", false, "wheel.yaml", "wheel"},
                       {"b", "cockpit-hud", false, "wheel.yaml", "wheel"},
                       {"c", "cockpit-assisted", false, "wheel.yaml", "wheel"},
                       {"d", "gesture", false, "mouse.yaml", "mouse"}};
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
    record::RunRecord first = test::TrialRun(42.0, true, 2);
    first.approach_s = 3.25;  // before the start line: kept apart, not scored
    // What could have spoiled it, kept with the trial; clamped forces are the safety at work, not a
    // flag.
    first.servo_rate_short = true;
    first.counters = {
        {"servo_forces_clamped", 5}, {"vehicle_watchdog_trips", 2}, {"link_states_missed", 0}};
    recorder.Save(first, store.TrialWriter(plan[0], 600.0));
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
  CHECK(trials[0].approach_s == 3.25);
  CHECK(trials[0].flags == "servo rate short; vehicle watchdog trips 2");
  CHECK(trials[1].flags.empty());
  CHECK(std::isnan(trials[1].approach_s));  // a run that did not measure it: NULL, not 0
  CHECK(recorder.LoadAll()[0].approach_s == 3.25);
  CHECK(trials[0].obstacles == 2);
  CHECK(trials[0].completed);
  CHECK(trials[1].lap_time_s == 600.0);  // the cap, as the thesis scored driver B
  CHECK_FALSE(trials[1].completed);
  CHECK(store.NextTrial()->position == 3);
  CHECK(store.TrialsDone("P1") == 2);
  CHECK(store.TrialsDone("P2") == 0);
  // Each trial's device, planned and driven with: the condition's.
  for (const PlannedTrial& t : store.Plan())
    CHECK(t.device == (t.condition == "d" ? "mouse" : "wheel"));
  CHECK(trials[0].device == plan[0].device);
  CHECK(trials[1].device == plan[1].device);

  SECTION("answers: once per participant, condition and questionnaire") {
    CHECK_FALSE(store.Answered("P1", plan[0].condition, "thesis"));
    store.SaveAnswers("P1", plan[0].condition, "thesis",
                      {{"easy_to_learn", "4"}, {"efficient", "3"}});
    CHECK(store.Answered("P1", plan[0].condition, "thesis"));
    CHECK_THROWS_AS(store.SaveAnswers("P1", plan[0].condition, "thesis", {{"easy_to_learn", "5"}}),
                    AlreadyAnswered);
    CHECK(store.Answers().size() == 2);
  }
  SECTION("redo takes a trial back once, keeping it as superseded; the next row is attempt 2") {
    CHECK(store.Redo("P1", 1, "test"));
    CHECK_FALSE(store.Redo("P1", 1, "test"));
    CHECK(store.NextTrial()->position == 1);
    recorder.Save(test::TrialRun(39.0), store.TrialWriter(plan[0], 600.0));
    CHECK(store.Trials()[0].attempt == 2);
    const std::vector<SupersededTrial> superseded = store.Superseded();
    REQUIRE(superseded.size() == 1);
    CHECK(superseded[0].trial.lap_time_s == 42.0);  // the row as it was
    CHECK(superseded[0].trial.attempt == 1);
    CHECK(superseded[0].trial.flags == "servo rate short; vehicle watchdog trips 2");
    CHECK(superseded[0].trial.approach_s == 3.25);
    CHECK(superseded[0].trial.device == plan[0].device);
    CHECK(superseded[0].why == "test");
  }
  SECTION("a synthetic study's flagged trial is run again once: the first attempt only") {
    CHECK_FALSE(store.RedoFlaggedOnce(plan[1]));  // not flagged: kept
    CHECK(store.RedoFlaggedOnce(plan[0]));
    CHECK(store.NextTrial()->position == 1);
    REQUIRE(store.Superseded().size() == 1);
    CHECK(store.Superseded()[0].why.find("flagged (servo rate short") == 0);
    record::RunRecord again = test::TrialRun(41.0);
    again.physics_rate_short = true;  // flagged again: kept this time
    recorder.Save(again, store.TrialWriter(plan[0], 600.0));
    CHECK_FALSE(store.RedoFlaggedOnce(plan[0]));
    CHECK(store.Trials()[0].attempt == 2);
    CHECK(store.Trials()[0].flags == "physics rate short");
    CHECK(store.Superseded().size() == 1);
  }
  SECTION("the experimenter's notes: several per trial, in the order written, across a restart") {
    store.SaveNote("P1", 1, "drove with the left hand only");
    store.SaveNote("P1", 1, "said the wheel felt heavy");
    store.SaveNote("P2", 0, "wears glasses");
    StudyStore again(recorder, config, plan);
    const std::vector<NoteRow> notes = again.Notes();
    REQUIRE(notes.size() == 3);
    CHECK(notes[0].text == "drove with the left hand only");
    CHECK(notes[1].position == 1);
    CHECK(notes[1].text == "said the wheel felt heavy");
    CHECK(notes[2].participant == "P2");
    CHECK(notes[2].position == 0);
  }
  SECTION("the practice lap is remembered per participant") {
    CHECK_FALSE(store.Practised("P2"));
    store.Event("practice interrupted", "P2", 0,
                "run 8: aborted from the console");  // offered again
    CHECK_FALSE(store.Practised("P2"));
    store.Event("practice", "P2", 0, "run 9");
    CHECK(store.Practised("P2"));
    CHECK_FALSE(store.Practised("P3"));
  }
  SECTION("a participant added in the console comes after the file's, and survives a restart") {
    store.AddParticipant("E", PlanParticipant(config, "E", 4));
    CHECK(store.Plan().size() == 20);
    CHECK(store.Plan().back().device == PlanParticipant(config, "E", 4).back().device);
    CHECK_FALSE(store.Plan().back().device.empty());
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
    CHECK_THROWS_WITH(
        StudyStore(recorder, changed, PlanTrials(changed)),
        Catch::Contains("design.order: balanced-latin-square, the file now says fixed") &&
            Catch::Contains("another name"));
    StudyConfig more = FourConditions(dir, 8);
    CHECK_THROWS_WITH(
        StudyStore(recorder, more, PlanTrials(more)),
        Catch::Contains("participants: P1, P2, P3, P4, the file now says P1, P2, P3, P4, P5"));
  }
}

namespace {

std::string FileText(const std::filesystem::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// `text` with its one `from` replaced by `to`.
std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  REQUIRE(text.find(from, at + 1) == std::string::npos);
  return text.replace(at, from.size(), to);
}

/// A small person study on a copy of the short test track beside it.
std::string ResumedStudy() {
  const auto source = std::filesystem::current_path();
  return "# a study resumed from a file that may have changed\n"
         "name: resumed\n"
         "description: first words\n"
         "run: " +
         (source / "config/haptel.yaml").string() +
         "\n"
         "track: track.yaml\n"
         "operators: person\n"
         "conditions:\n"
         "  - {name: a, interface: cockpit}\n"
         "  - {name: b, interface: gesture}\n"
         "design:\n"
         "  order: balanced-latin-square\n"
         "practice: false\n"
         "trial_cap_s: 5\n"
         "questionnaires: [thesis]\n"
         "participants:\n"
         "  - {id: P1}\n"
         "  - {id: P2}\n";
}

}  // namespace

TEST_CASE(
    "A study resumed from a changed file is refused, naming each changed key and both values") {
  const auto dir = test::ScratchDir("study-store-changed");
  std::filesystem::remove(dir / "s.db");
  const auto track = dir / "track.yaml";
  std::filesystem::copy_file("config/tracks/test-short.yaml", track,
                             std::filesystem::copy_options::overwrite_existing);
  const auto file = test::WriteFile(dir / "study.yaml", ResumedStudy());
  const auto db = dir / "s.db";
  record::Recorder recorder(db);
  {
    const StudyConfig planned = LoadStudy(file);
    StudyStore store(recorder, planned, PlanTrials(planned));
    CHECK_FALSE(store.resumed());
    recorder.Save(test::TrialRun(4.0), store.TrialWriter(store.Plan()[0], planned.trial_cap_s));
  }
  // The file rewritten as `text`, loaded and planned as `haptel study run` does.
  auto resume = [&](const std::string& text) {
    test::WriteFile(file, text);
    const StudyConfig config = LoadStudy(file);
    return StudyStore(recorder, config, PlanTrials(config));
  };
  auto refusal = [&](const std::string& text) {
    return test::WhatOf<std::runtime_error>([&] { resume(text); });
  };
  const std::string study = ResumedStudy();

  SECTION("the same study resumes, whatever its comments, spacing, key order and description") {
    std::string same = Replaced(study, "trial_cap_s: 5\n", "");
    same = Replaced(same, "description: first words", "description: other words  # and a comment");
    same += "trial_cap_s: 5.0   # moved to the end\n";
    StudyStore store = resume(same);
    CHECK(store.resumed());
    CHECK(store.Trials().size() == 1);
    CHECK(store.NextTrial()->position == 2);
  }
  SECTION("an open study with participants added in the console resumes, keeping them") {
    {
      StudyStore store = resume(study);
      store.AddParticipant("P3", PlanParticipant(LoadStudy(file), "P3", 2));
      store.AddParticipant("P4", PlanParticipant(LoadStudy(file), "P4", 3));
    }
    StudyStore store = resume(study);
    CHECK(store.Participants() == std::vector<std::string>{"P1", "P2", "P3", "P4"});
    CHECK(store.Plan().size() == 8);
  }
  SECTION("another track") {
    const std::string what = refusal(Replaced(
        study, "track: track.yaml",
        "track: " + (std::filesystem::current_path() / "config/tracks/grand-prix.yaml").string()));
    CHECK_THAT(what, Catch::Contains("study 'resumed' in " + db.string() +
                                     " was planned with track: track.yaml, "
                                     "the file now says ") &&
                         Catch::Contains("config/tracks/grand-prix.yaml") &&
                         !Catch::Contains("track.name") &&
                         Catch::Contains("a changed study is a new one: give it another name"));
  }
  SECTION("the track file edited under the same name") {
    const std::string planned_track = FileText(track);
    test::WriteFile(track, Replaced(planned_track, "  - {along: 0.2}", "  - {along: 0.25}"));
    CHECK_THAT(refusal(study), Catch::Contains("track.gates[1]: along 0.2 m, width 0.4 m, the file "
                                               "now says along 0.25 m, width 0.4 m"));
    test::WriteFile(track, planned_track);
  }
  SECTION("another cap") {
    CHECK_THAT(refusal(Replaced(study, "trial_cap_s: 5", "trial_cap_s: 3600")),
               Catch::Contains("was planned with trial_cap_s: 5, the file now says 3600;"));
  }
  SECTION("a condition given another interface under its name") {
    CHECK_THAT(refusal(Replaced(study, "{name: b, interface: gesture}",
                                "{name: b, interface: cockpit-hud}")),
               Catch::Contains("conditions.b.interface: gesture, the file now says cockpit-hud"));
  }
  SECTION("a condition renamed") {
    CHECK_THAT(
        refusal(Replaced(study, "{name: b, interface: gesture}", "{name: g, interface: gesture}")),
        Catch::Contains("conditions: a, b, the file now says a, g") &&
            Catch::Contains("conditions.b.interface: gesture, the file now says (absent)"));
  }
  SECTION("a condition driven with another device") {
    const auto udp = std::filesystem::current_path() / "config/devices/udp.yaml";
    const std::string what =
        refusal(Replaced(study, "{name: b, interface: gesture}",
                         "{name: b, interface: gesture, device: " + udp.string() + "}"));
    CHECK_THAT(what, Catch::Contains("conditions.b.device: ") &&
                         Catch::Contains("devices/sim.yaml, the file now says ") &&
                         Catch::Contains("devices/udp.yaml"));
  }
  SECTION("other questionnaires") {
    CHECK_THAT(refusal(Replaced(study, "questionnaires: [thesis]", "questionnaires: [tlx, sus]")),
               Catch::Contains("questionnaires: thesis, the file now says tlx, sus"));
  }
  SECTION("another order") {
    CHECK_THAT(refusal(Replaced(study, "order: balanced-latin-square", "order: fixed")),
               Catch::Contains("design.order: balanced-latin-square, the file now says fixed"));
  }
  SECTION("a practice lap") {
    CHECK_THAT(refusal(Replaced(study, "practice: false", "practice: true")),
               Catch::Contains("practice: false, the file now says true"));
  }
  SECTION("participants added to the file's list: the console adds them to an open study") {
    CHECK_THAT(refusal(study + "  - {id: P3}\n  - {id: P4}\n"),
               Catch::Contains("participants: P1, P2, the file now says P1, P2, P3, P4") &&
                   Catch::Contains("added in the console"));
  }
  SECTION("several changes at once: each is named") {
    std::string both = Replaced(study, "trial_cap_s: 5", "trial_cap_s: 3600");
    both = Replaced(both, "questionnaires: [thesis]", "questionnaires: []");
    const std::string what = refusal(both);
    CHECK_THAT(what, Catch::Contains("trial_cap_s: 5, the file now says 3600") &&
                         Catch::Contains("questionnaires: thesis, the file now says (none)"));
  }
  // A refused resume writes nothing, and the study resumes once the file is put back.
  StudyStore store = resume(study);
  CHECK(store.resumed());
  CHECK(store.Plan().size() >= 4);
  CHECK(store.Trials().size() == 1);
}

TEST_CASE("A simulated driver's profile is part of the study") {
  const auto dir = test::ScratchDir("study-store-profiles");
  std::filesystem::remove(dir / "s.db");
  const auto source = std::filesystem::current_path();
  const std::string study =
      "name: drivers\nrun: " + (source / "config/haptel.yaml").string() +
      "\noperators: synthetic\nconditions:\n  - {name: a, interface: cockpit}\n"
      "  - {name: b, interface: gesture}\nprofiles:\n"
      "  p: {steering_noise: 0.02, seed: 7}\n  unused: {hud_use: 0.5}\n"
      "participants:\n  - {id: A, profile: p}\n  - {id: B, profile: p}\n";
  const auto file = dir / "study.yaml";
  record::Recorder recorder(dir / "s.db");
  auto resume = [&](const std::string& text) {
    test::WriteFile(file, text);
    const StudyConfig config = LoadStudy(file);
    return StudyStore(recorder, config, PlanTrials(config));
  };
  CHECK_FALSE(resume(study).resumed());
  // A profile nobody drives with changes no trial.
  CHECK(resume(Replaced(study, "unused: {hud_use: 0.5}", "unused: {hud_use: 0.9}")).resumed());
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] {
               resume(Replaced(study, "p: {steering_noise: 0.02, seed: 7}",
                               "p: {steering_noise: 0.03, seed: 7}"));
             }),
             Catch::Contains("profiles.p.steering_noise: 0.02, the file now says 0.03"));
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] {
               resume(Replaced(study, "p: {steering_noise: 0.02, seed: 7}",
                               "p: {steering_noise: 0.02, seed: 8}"));
             }),
             Catch::Contains("profiles.p.seed: 7, the file now says 8"));
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] {
               resume(Replaced(study, "{id: B, profile: p}", "{id: B, profile: unused}"));
             }),
             Catch::Contains("participants.B.profile: p, the file now says unused"));
  // No console adds a simulated driver, and none is added to the file's list of an open study
  // either.
  CHECK_THAT(test::WhatOf<std::runtime_error>(
                 [&] { resume(study + "  - {id: C, profile: p}\n  - {id: D, profile: p}\n"); }),
             Catch::Contains("participants: A, B, the file now says A, B, C, D") &&
                 !Catch::Contains("console"));
}

TEST_CASE(
    "A study planned before the database kept definitions resumes once, then is held to its file") {
  const auto dir = test::ScratchDir("study-store-v5");
  const auto db = dir / "v5.db";
  std::filesystem::remove(db);
  const auto track = dir / "track.yaml";
  std::filesystem::copy_file("config/tracks/test-short.yaml", track,
                             std::filesystem::copy_options::overwrite_existing);
  const auto file = test::WriteFile(dir / "study.yaml", ResumedStudy());
  {
    record::Recorder recorder(db);
    const StudyConfig config = LoadStudy(file);
    StudyStore store(recorder, config, PlanTrials(config));
  }
  // What a v5 database holds: the same tables without the definition (v6)
  // and the runs' prediction and link fault (v7), the approach (v8), the
  // video's bitrate and stale time (v9), the notes and the superseded
  // trials (v10), the simulated-time speed-up (v11), the servo controller's
  // errors (v12), the runs' engagement and device use (v13), the trials'
  // devices (v14), the runs' session files (v15), the truth's lap (v16).
  {
    sqlite3* raw = nullptr;
    REQUIRE(sqlite3_open(db.c_str(), &raw) == SQLITE_OK);
    REQUIRE(
        sqlite3_exec(
            raw,
            "ALTER TABLE studies DROP COLUMN definition_form; ALTER TABLE runs DROP COLUMN "
            "predict; "
            "ALTER TABLE runs DROP COLUMN link_fault; ALTER TABLE runs DROP COLUMN "
            "prediction_error_m_p50; "
            "ALTER TABLE runs DROP COLUMN prediction_error_m_p95; ALTER TABLE runs DROP COLUMN "
            "approach_s; "
            "ALTER TABLE study_trials DROP COLUMN approach_s; ALTER TABLE study_trials DROP COLUMN "
            "flags; "
            "ALTER TABLE runs DROP COLUMN video_kbps; ALTER TABLE runs DROP COLUMN video_stale_s; "
            "ALTER TABLE runs DROP COLUMN speedup; ALTER TABLE runs DROP COLUMN controller_errors; "
            "ALTER TABLE runs DROP COLUMN disengaged_s; ALTER TABLE runs DROP COLUMN "
            "pseudo_haptic_gain_mean; ALTER TABLE runs DROP COLUMN ff_effects_played; "
            "ALTER TABLE study_plan DROP COLUMN device; ALTER TABLE study_trials DROP COLUMN "
            "device; ALTER TABLE runs DROP COLUMN session_file; "
            "ALTER TABLE runs DROP COLUMN completed_truth; ALTER TABLE runs DROP COLUMN "
            "lap_time_truth_s; ALTER TABLE runs DROP COLUMN lap_time_truth_projected; "
            "ALTER TABLE runs DROP COLUMN gates_truth_passed; ALTER TABLE runs DROP COLUMN "
            "gates_truth_missed; "
            "DROP TABLE study_notes; DROP TABLE study_superseded_trials; PRAGMA user_version = 5",
            nullptr, nullptr, nullptr) == SQLITE_OK);
    sqlite3_close(raw);
  }
  record::Recorder recorder(db);  // migrated to v16: the study has no definition on record
  auto resume = [&](const std::string& text) {
    test::WriteFile(file, text);
    const StudyConfig config = LoadStudy(file);
    return StudyStore(recorder, config, PlanTrials(config));
  };
  const std::string changed_cap = Replaced(ResumedStudy(), "trial_cap_s: 5", "trial_cap_s: 60");
  {
    // Its plan is all there is to check, and it matches: it resumes, and keeps the file's
    // definition from now on.
    StudyStore store = resume(changed_cap);
    CHECK(store.resumed());
  }
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] { resume(ResumedStudy()); }),
             Catch::Contains("trial_cap_s: 60, the file now says 5"));
  CHECK(resume(changed_cap).resumed());
  // A plan that differs is refused as before.
  CHECK_THAT(test::WhatOf<std::runtime_error>(
                 [&] { resume(ResumedStudy() + "  - {id: P3}\n  - {id: P4}\n"); }),
             Catch::Contains("participants: P1, P2, the file now says P1, P2, P3, P4"));
}

TEST_CASE("A study's definition reads back as written, escapes and all") {
  const std::vector<DefiningValue> values = {
      {"form", "1"}, {"odd: key", "a\nb\\c: d"}, {"empty", ""}};
  const std::vector<DefiningValue> back = ParseDefinition(DefinitionText(values));
  REQUIRE(back.size() == values.size());
  for (size_t i = 0; i < values.size(); ++i) {
    CHECK(back[i].key == values[i].key);
    CHECK(back[i].value == values[i].value);
  }
  CHECK(DefinitionChanges(values, back).empty());
  // Another version's form is compared only on the keys both know.
  const std::vector<DefiningValue> newer = {
      {"form", "2"}, {"odd: key", "a\nb\\c: d"}, {"new", "x"}};
  CHECK(DefinitionChanges(values, newer).empty());
}

TEST_CASE(
    "A study's file deleted or replaced while it runs: its writes are refused, not acknowledged "
    "into the void") {
  // SQLite in WAL mode would write on into the unlinked file, and the console
  // would answer 303 for a participant or a note that no file keeps.
  const auto dir = test::ScratchDir("study-store-moved");
  const StudyConfig config = FourConditions(dir, 4);
  const std::vector<PlannedTrial> plan = PlanTrials(config);
  const auto db = dir / "s.db";
  record::Recorder recorder(db);
  StudyStore store(recorder, config, plan);
  SECTION("deleted") {
    for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(db.string() + suffix);
  }
  SECTION("replaced") {
    std::filesystem::rename(db, dir / "moved.db");
    record::Recorder other(db);  // a new, empty file in its place
  }
  const std::string participant = test::WhatOf<std::runtime_error>(
      [&] { store.AddParticipant("P9", PlanParticipant(config, "P9", 4)); });
  CHECK_THAT(participant, Catch::Contains("deleted or replaced"));
  CHECK_THAT(participant, Catch::Contains(db.string()));
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] { store.SaveNote("P1", 0, "kept?"); }),
             Catch::Contains("deleted or replaced"));
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] {
               store.SaveAnswers("P1", "a", "q", {{"item", "1"}});
             }),
             Catch::Contains("deleted or replaced"));
  CHECK_THAT(test::WhatOf<std::runtime_error>([&] { store.Event("note", "P1", 0, "x"); }),
             Catch::Contains("deleted or replaced"));
}
