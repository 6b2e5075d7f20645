// The study report on the thesis's own data (tables 8.1–8.4: drivers A–E,
// lap times in s, obstacles), recorded through the real store: the tables,
// the ranks, the statistics, the CSV, the plots and the page.
#include <catch2/catch.hpp>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "haptel/config/study.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/study/report.hpp"
#include "haptel/study/store.hpp"
#include "study_test_run.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::study;

namespace {

const std::vector<std::string> kConditions = {"cockpit", "cockpit-hud", "assisted", "gesture"};
const std::vector<std::string> kDrivers = {"A", "B", "C", "D", "E"};
// Tables 8.1–8.4 (B reached the 10-minute cap with both plain cockpits).
const double kTimes[4][5] = {{210, 600, 245, 320, 310},
                             {225, 600, 220, 405, 240},
                             {170, 150, 190, 325, 220},
                             {120, 120, 110, 210, 200}};
const int kObstacles[4][5] = {{1, 5, 1, 1, 1}, {1, 5, 0, 1, 0}, {0, 1, 1, 1, 0}, {0, 1, 1, 0, 0}};

std::string Read(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The thesis's study recorded in `db`: every trial, and two answers; with
/// `sessions`, each trial's session file (a stand-in's bytes) in
/// dir/sessions/, named in its run.
void RecordThesis(const std::filesystem::path& dir, const std::filesystem::path& db,
                  int drivers = 5, bool sessions = false) {
  StudyConfig config;
  config.file = dir / "thesis.yaml";
  test::WriteFile(config.file, "name: thesis\n");
  config.name = "thesis";
  config.trial_cap_s = 600;
  config.order = StudyOrder::kFixed;
  for (const std::string& c : kConditions) config.conditions.push_back({c, c});
  std::vector<PlannedTrial> plan;
  for (int p = 0; p < drivers; ++p) {
    config.participants.push_back({kDrivers[static_cast<size_t>(p)], ""});
    for (int c = 0; c < 4; ++c)
      plan.push_back(
          {kDrivers[static_cast<size_t>(p)], c + 1, kConditions[static_cast<size_t>(c)], 1});
  }
  record::Recorder recorder(db);
  StudyStore store(recorder, config, plan);
  if (sessions) std::filesystem::create_directories(dir / "sessions");
  for (const PlannedTrial& t : plan) {
    const size_t c = static_cast<size_t>(t.position - 1);
    const size_t p = static_cast<size_t>(
        std::find(kDrivers.begin(), kDrivers.end(), t.participant) - kDrivers.begin());
    const double lap = kTimes[c][p];
    record::RunRecord run = test::TrialRun(lap, lap < 600, kObstacles[c][p]);
    if (sessions) {
      const auto file =
          dir / "sessions" / (t.participant + "-" + std::to_string(t.position) + ".mcap");
      test::WriteFile(file, "MCAP stand-in");
      run.session_file = file.string();
    }
    recorder.Save(run, store.TrialWriter(t, config.trial_cap_s));
  }
  store.SaveAnswers("A", "gesture", "thesis",
                    {{"easy_to_learn", "3"}, {"remarks", "<script>alert(1)</script>, \"odd\""}});
  store.SaveAnswers("A", "gesture", "rating", {{"rating", "2"}, {"score", "2"}});
  // Remarks a spreadsheet would run as formulas, and a negative number it must not touch.
  store.SaveAnswers("B", "gesture", "thesis",
                    {{"remarks", "=HYPERLINK(\"http://x.example\",\"see\")"},
                     {"efficient", "@SUM(1)"},
                     {"easy_to_learn", "-2"}});
}

}  // namespace

TEST_CASE("The report on the thesis's data gives its tables, ranks and statistics") {
  const auto dir = test::ScratchDir("study-report");
  const auto db = dir / "thesis.db";
  RecordThesis(dir, db);
  const StudyResults results = LoadStudyResults(db, "thesis");
  REQUIRE(results.trials.size() == 20);
  REQUIRE(results.conditions == kConditions);
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);

  // Times as recorded, totals as the thesis adds them (28m05, 28m10, 17m35, 12m40).
  const double totals[4] = {1685, 1690, 1055, 760};
  for (size_t c = 0; c < 4; ++c) {
    INFO(kConditions[c]);
    CHECK(report.conditions[c].total_lap_time_s == Approx(totals[c]));
    for (size_t p = 0; p < 5; ++p) CHECK(report.conditions[c].lap_time_s[p] == kTimes[c][p]);
  }
  // Gesture first for every driver (table 8.4); B's two capped cockpits tie at 3.5.
  for (size_t p = 0; p < 5; ++p) CHECK(report.conditions[3].rank[p] == 1.0);
  CHECK(report.conditions[0].rank[1] == 3.5);
  CHECK(report.conditions[1].rank[1] == 3.5);
  // A: assisted 170 < cockpit 210 < hud 225: 2nd, 3rd, 4th as in tables 8.1–8.3.
  CHECK(report.conditions[2].rank[0] == 2.0);
  CHECK(report.conditions[0].rank[0] == 3.0);
  CHECK(report.conditions[1].rank[0] == 4.0);
  CHECK(report.conditions[0].unfinished == 1);

  // The statistics equal SciPy's for this data (tests/study/stats: friedmanchisquare).
  REQUIRE(report.analysis);
  CHECK(report.analysis->friedman.chi_square == Approx(12.183673469387752).epsilon(1e-12));
  CHECK(report.analysis->friedman.p_value_asymptotic ==
        Approx(0.0067797401305199397).epsilon(1e-9));
  // 5 participants, 4 conditions: the exact p (9168 of 24^5 orderings; tests/study/stats).
  CHECK(report.analysis->friedman.p_exact);
  CHECK(report.analysis->friedman.p_value == Approx(9168.0 / 7962624.0).epsilon(1e-9));
  CHECK(report.analysis->friedman.kendall_w == Approx(0.812244897959184).epsilon(1e-12));
  CHECK(report.participants_used.size() == 5);

  // The files.
  const ReportFiles files = WriteReport(results, report, dir / "out");
  const std::string trials = Read(files.trials_csv);
  CHECK(trials.rfind(
            "study,participant,condition,device,position,lap_time_s,approach_s,completed,obstacles",
            0) == 0);
  CHECK(trials.find("\nthesis,B,cockpit,,1,600.000,,false,5,") != std::string::npos);
  CHECK(trials.find("\nthesis,E,gesture,,4,200.000,,true,0,") != std::string::npos);
  CHECK(std::count(trials.begin(), trials.end(), '\n') == 21);
  const std::string answers = Read(files.answers_csv);
  CHECK(
      answers.find("thesis,A,gesture,thesis,remarks,\"<script>alert(1)</script>, \"\"odd\"\"\"") !=
      std::string::npos);
  // Formulas are written as text (after a single quote); numbers as they are.
  CHECK(answers.find("thesis,B,gesture,thesis,remarks,\"'=HYPERLINK(\"\"http://"
                     "x.example\"\",\"\"see\"\")\"") != std::string::npos);
  CHECK(answers.find("thesis,B,gesture,thesis,efficient,\"'@SUM(1)\"") != std::string::npos);
  CHECK(answers.find("thesis,B,gesture,thesis,easy_to_learn,-2\n") != std::string::npos);
  CHECK(answers.find(",=") == std::string::npos);
  for (const auto& png : {files.lap_times_png, files.ranks_png, files.ratings_png}) {
    INFO(png);
    const cv::Mat image = cv::imread(png.string());
    REQUIRE_FALSE(image.empty());
    CHECK(image.cols >= 600);
    CHECK(image.rows >= 300);
  }
  const std::string html = Read(files.html);
  CHECK(html.find("&lt;script&gt;alert(1)&lt;/script&gt;") != std::string::npos);
  CHECK(html.find("<script>") == std::string::npos);
  CHECK(html.find("<caption>assisted</caption>") != std::string::npos);
  CHECK(html.find("lap_times.png") != std::string::npos);

  const std::string json = ReportJson(results, report, files);
  CHECK(json.find("\"friedman_chi2\":12.18") != std::string::npos);
  // Which p it is, and the χ² one beside it.
  CHECK(json.find("\"friedman_p\":0.00115") != std::string::npos);
  CHECK(json.find("\"friedman_p_exact\":true") != std::string::npos);
  CHECK(json.find("\"friedman_p_asymptotic\":0.00677") != std::string::npos);
  const std::string text = FormatReport(results, report);
  CHECK(text.find("p = 0.0012 (exact; chi2 approximation 0.0068)") != std::string::npos);
  CHECK(json.find("\"participants_used\":5") != std::string::npos);
  CHECK(json.find("\"method\":\"Nemenyi (Demšar 2006), alpha 0.05\"") != std::string::npos);
  CHECK(std::count(json.begin(), json.end(), '\n') == 0);
}

TEST_CASE("lap_times.png marks capped laps apart, with a legend entry") {
  const auto dir = test::ScratchDir("study-report-capped");
  const auto db = dir / "thesis.db";
  RecordThesis(dir, db);
  const StudyResults results = LoadStudyResults(db, "thesis");
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  // The same times, as if B had finished both cockpits at the cap: only the marking differs.
  StudyResults finished = results;
  for (StudyResults::Trial& t : finished.trials) t.completed = true;
  DrawLapTimes(results, report, dir / "capped.png");
  DrawLapTimes(finished, report, dir / "finished.png");
  const cv::Mat capped = cv::imread((dir / "capped.png").string());
  const cv::Mat plain = cv::imread((dir / "finished.png").string());
  REQUIRE_FALSE(capped.empty());
  REQUIRE(capped.size() == plain.size());
  cv::Mat difference;
  cv::absdiff(capped, plain, difference);
  cv::cvtColor(difference, difference, cv::COLOR_BGR2GRAY);
  // B's two capped points (a marker, not a dot) and the legend's entry (bottom right).
  CHECK(cv::countNonZero(difference) > 200);
  const cv::Mat legend = difference(cv::Rect(capped.cols - 260, capped.rows - 40, 260, 40));
  CHECK(cv::countNonZero(legend) > 50);
}

TEST_CASE("The report marks capped and flagged trials in its tables and lists what flagged them") {
  const auto dir = test::ScratchDir("study-report-flagged");
  const auto db = dir / "thesis.db";
  RecordThesis(dir, db);
  StudyResults results = LoadStudyResults(db, "thesis");
  for (StudyResults::Trial& t : results.trials) {
    if (t.participant == "A" && t.condition == "cockpit") t.flags = "physics rate short";
  }
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  const std::string text = FormatReport(results, report);
  CHECK(text.find(" 210.00!") != std::string::npos);  // A's cockpit: flagged
  CHECK(text.find(" 600.00*") != std::string::npos);  // B's cockpit: capped
  CHECK(text.find("A, cockpit (position 1, run ") != std::string::npos);
  CHECK(text.find("): physics rate short") != std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "out");
  const std::string html = Read(files.html);
  CHECK(html.find("<td>210.00!</td>") != std::string::npos);
  CHECK(html.find("<td>600.00*</td>") != std::string::npos);
  CHECK(html.find("<h2>Flagged trials</h2>") != std::string::npos);
  const std::string trials = Read(files.trials_csv);
  CHECK(trials.find(",attempt,flags,over_reference_percent\n") != std::string::npos);
  // No reference lap on this track: the percentage's column is empty.
  CHECK(trials.find(",physics rate short,\n") != std::string::npos);
}

TEST_CASE("The report links each trial to its session file and says which are gone") {
  const auto dir = test::ScratchDir("study-report-sessions");
  const auto db = dir / "thesis.db";
  RecordThesis(dir, db, 2, /*sessions=*/true);
  const auto deleted = dir / "sessions" / "B-3.mcap";
  REQUIRE(std::filesystem::remove(deleted));
  const StudyResults results = LoadStudyResults(db, "thesis");
  int missing = 0;
  for (const StudyResults::Trial& t : results.trials) {
    CHECK(
        t.session_file ==
        (dir / "sessions" / (t.participant + "-" + std::to_string(t.position) + ".mcap")).string());
    missing += t.session_missing ? 1 : 0;
  }
  CHECK(missing == 1);
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  const std::string text = FormatReport(results, report);
  CHECK(text.find("session files") != std::string::npos);
  CHECK(text.find("A, cockpit (position 1, run 1): " + (dir / "sessions" / "A-1.mcap").string() +
                  "\n") != std::string::npos);
  CHECK(text.find(deleted.string() + " (MISSING: deleted or moved)") != std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "out");
  const std::string html = Read(files.html);
  CHECK(html.find("<ul id=\"sessions\">") != std::string::npos);
  CHECK(html.find("<a href=\"file://" + (dir / "sessions" / "A-1.mcap").string()) !=
        std::string::npos);
  CHECK(html.find(deleted.string() + " <strong>missing</strong>") != std::string::npos);
}

TEST_CASE("The report says what it lacks instead of failing") {
  const auto dir = test::ScratchDir("study-report-lacks");
  const auto db = dir / "one.db";
  RecordThesis(dir, db, 1);  // one driver: tables, no statistics
  const StudyResults results = LoadStudyResults(db, "thesis");
  const StudyReport report = ComputeReport(results, PostHocMethod::kWilcoxonHolm);
  CHECK_FALSE(report.analysis);
  CHECK(report.why_no_statistics.find("at least 2 participants") != std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "out");
  CHECK(std::filesystem::exists(files.lap_times_png));
  CHECK(ReportJson(results, report, files).find("\"friedman_chi2\":null") != std::string::npos);
  CHECK(ReportJson(results, report, files).find("\"friedman_p_exact\":null") != std::string::npos);

  CHECK_THROWS_WITH(LoadStudyResults(db, "other"),
                    Catch::Contains("no study 'other'") && Catch::Contains("thesis"));
  CHECK_THROWS_WITH(LoadStudyResults(dir / "none.db", "thesis"), Catch::Contains("no such file"));
}

TEST_CASE("The power curve's legend names the test the power is computed by") {
  // power.hpp: the mixed model's condition is Satterthwaite's F test, not
  // the likelihood-ratio test (issue 40: the legend said "LRT").
  const std::string mixed = kPowerMixedModelLegend;
  CHECK(mixed.find("Satterthwaite") != std::string::npos);
  CHECK(mixed.find("LRT") == std::string::npos);
  CHECK(std::string(kPowerFriedmanLegend) == "Friedman");
}
