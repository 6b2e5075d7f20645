// The report's mixed model and baseline on a study recorded through the real
// store: the balanced Latin-square data set of tests/study/stats (whose lme4
// values are there), a track with a reference lap, and the cases a study
// meets on its way (one participant, a fixed order).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
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

struct Lap {
  int participant;
  int condition;
  int position;
  double lap_time_s;
};

// tests/study/stats/lme4_reference.R's balanced data set.
const std::vector<Lap> kBalanced = {
    {1, 0, 1, 113.51}, {1, 1, 2, 100.92}, {1, 3, 3, 48.99}, {1, 2, 4, 74.44}, {2, 1, 1, 105.82},
    {2, 2, 2, 70.27},  {2, 0, 3, 63.68},  {2, 3, 4, 41.47}, {3, 2, 1, 40.29}, {3, 3, 2, 30.67},
    {3, 1, 3, 55.06},  {3, 0, 4, 47.46},  {4, 3, 1, 29.48}, {4, 0, 2, 37.51}, {4, 2, 3, 39.78},
    {4, 1, 4, 45.81},  {5, 0, 1, 33.64},  {5, 1, 2, 46.47}, {5, 3, 3, 27.83}, {5, 2, 4, 42.35},
    {6, 1, 1, 86.39},  {6, 2, 2, 60.50},  {6, 0, 3, 57.69}, {6, 3, 4, 35.46}, {7, 2, 1, 71.43},
    {7, 3, 2, 33.67},  {7, 1, 3, 61.43},  {7, 0, 4, 59.86}, {8, 3, 1, 57.76}, {8, 0, 2, 78.83},
    {8, 2, 3, 65.04},  {8, 1, 4, 85.67}};

std::string Read(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

/// "P1": built piecewise, GCC 12 warns falsely (-Wrestrict) on "literal" + string.
std::string Participant(int p) {
  std::string id(1, 'P');
  id += std::to_string(p);
  return id;
}

/// Records `laps` as study "lmm" in `db`, on a track whose reference lap is
/// `reference_lap` ("" for none).
void Record(const std::filesystem::path& dir, const std::filesystem::path& db,
            const std::vector<Lap>& laps, const std::string& reference_lap) {
  StudyConfig config;
  config.file = dir / "lmm.yaml";
  test::WriteFile(config.file, "name: lmm\n");
  std::string track("name: square\ncorridor_width: 1.0\nlap_cap_s: 600\n");
  track += reference_lap;
  track += "centerline: [[0, 0], [4, 0], [4, 3], [0, 3]]\ngates: [{along: 1.0}]\n";
  config.track = test::WriteFile(dir / "track.yaml", track);
  config.name = "lmm";
  config.trial_cap_s = 600;
  config.order = StudyOrder::kBalancedLatinSquare;
  for (const std::string& c : kConditions) config.conditions.push_back({c, c});
  std::vector<PlannedTrial> plan;
  for (const Lap& lap : laps) {
    if (lap.position == 1) config.participants.push_back({Participant(lap.participant), ""});
    plan.push_back({Participant(lap.participant), lap.position,
                    kConditions[static_cast<size_t>(lap.condition)], 1});
  }
  record::Recorder recorder(db);
  StudyStore store(recorder, config, plan);
  for (size_t i = 0; i < laps.size(); ++i) {
    recorder.Save(test::TrialRun(laps[i].lap_time_s),
                  store.TrialWriter(plan[i], config.trial_cap_s));
  }
}

/// `value` as the report prints a p: 4 decimals.
std::string Fixed4(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", value);
  return text;
}

double NumberAfter(const std::string& json, const std::string& key) {
  const size_t at = json.find(key);
  REQUIRE(at != std::string::npos);
  return std::strtod(json.c_str() + at + key.size(), nullptr);
}

}  // namespace

TEST_CASE(
    "The report fits the mixed model to log lap times and measures laps against the reference "
    "lap") {
  const auto dir = test::ScratchDir("study-report-lmm");
  const auto db = dir / "lmm.db";
  Record(dir, db, kBalanced, "reference_lap_s: 30\n");
  const StudyResults results = LoadStudyResults(db, "lmm");
  REQUIRE(results.reference_lap_s.has_value());
  CHECK(*results.reference_lap_s == 30.0);
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  REQUIRE(report.mixed_model.has_value());
  const MixedModelResult& m = *report.mixed_model;
  // lme4 on the same data (tests/study/stats/test_mixed_model.cpp).
  REQUIRE(m.conditions[3].effect.has_value());
  CHECK(m.conditions[3].effect->estimate == Approx(-0.4386688746).margin(1e-6));
  CHECK(m.conditions[3].effect->standard_error == Approx(0.06436647928).margin(1e-6));
  REQUIRE(m.position.has_value());
  CHECK(m.position->estimate == Approx(-0.04898715447).margin(1e-6));

  const std::string text = FormatReport(results, report);
  CHECK(text.find("mixed model: log(lap time) ~ condition + position + (1 | participant), 32 "
                  "trials of 8") != std::string::npos);
  CHECK(text.find("clock: the lap clock") != std::string::npos);
  CHECK(text.find("Satterthwaite") != std::string::npos);
  CHECK(text.find("Satterthwaite's F = 34.494 on 3 and 20.0 df") != std::string::npos);
  CHECK(text.find("likelihood-ratio chi2 = 43.689, df = 3") != std::string::npos);
  // gesture: exp(-0.4387) = 0.64 x the cockpit's lap time.
  CHECK(text.find("0.64 (") != std::string::npos);
  // The baseline: P1's cockpit lap 113.51 s is 278 % over 30 s.
  CHECK(text.find("baseline: reference lap 30.00 s") != std::string::npos);
  CHECK(text.find("+278%") != std::string::npos);

  const ReportFiles files = WriteReport(results, report, dir / "out");
  // trials.csv says each lap's percentage over the reference lap, as the
  // table does: P1's cockpit lap, 113.51 s against 30 s.
  const std::string trials = Read(files.trials_csv);
  CHECK(trials.rfind("study,participant,condition,device,position,lap_time_s,", 0) == 0);
  CHECK(trials.find(",flags,over_reference_percent\n") != std::string::npos);
  CHECK(trials.find(",113.510,") != std::string::npos);
  CHECK(trials.find(",278.37\n") != std::string::npos);
  const cv::Mat plot = cv::imread(files.model_means_png.string());
  REQUIRE_FALSE(plot.empty());
  CHECK(plot.cols >= 600);
  CHECK(Read(files.html).find("model_means.png") != std::string::npos);
  CHECK(Read(files.html).find("mixed model:") != std::string::npos);

  const std::string json = ReportJson(results, report, files);
  CHECK(json.find("\"lmm\":{") != std::string::npos);
  CHECK(json.find("\"why_no_lmm\":\"\"") != std::string::npos);
  CHECK(json.find("\"reference\":\"cockpit\"") != std::string::npos);
  const size_t gesture = json.find("{\"name\":\"gesture\",\"reference\":false");
  REQUIRE(gesture != std::string::npos);
  const std::string gesture_json = json.substr(gesture);
  CHECK(NumberAfter(gesture_json, "\"estimate\":") == Approx(-0.4386688746).margin(1e-6));
  CHECK(NumberAfter(gesture_json, "\"ci_low\":") == Approx(-0.5729349976).margin(1e-5));
  CHECK(NumberAfter(gesture_json, "\"ci_high\":") == Approx(-0.3044027516).margin(1e-5));
  CHECK(NumberAfter(gesture_json, "\"p\":") == Approx(1.262338317e-06).epsilon(1e-3));
  CHECK(NumberAfter(json, "\"position\":{\"estimate\":") == Approx(-0.04898715447).margin(1e-6));
  CHECK(json.find("\"method\":\"Satterthwaite F\"") != std::string::npos);
  // lmerTest's anova(fit) on these data: F 34.494 on 3 and 20 df, p 4.24e-08.
  CHECK(NumberAfter(json, "\"den_df\":") == Approx(20.0).epsilon(1e-3));
  CHECK(NumberAfter(json, "\"lrt_p\":") == Approx(1.757197026e-09).epsilon(1e-3));
  CHECK(json.find("\"boundary\":false") != std::string::npos);
  CHECK(NumberAfter(json, "\"baseline\":{\"reference_lap_s\":") == 30.0);
  CHECK(NumberAfter(json, "\"lap_time_s\":113.51,\"over_reference_percent\":") ==
        Approx(100.0 * (113.51 - 30.0) / 30.0));
  CHECK(json.find("nan") == std::string::npos);
  CHECK(json.find("inf") == std::string::npos);
  CHECK(std::count(json.begin(), json.end(), '\n') == 0);
}

TEST_CASE("The report's mixed model with one participant, and without a reference lap, says why") {
  const auto dir = test::ScratchDir("study-report-lmm-one");
  const auto db = dir / "one.db";
  std::vector<Lap> one;
  for (const Lap& lap : kBalanced) {
    if (lap.participant == 1) one.push_back(lap);
  }
  Record(dir, db, one, "");
  const StudyResults results = LoadStudyResults(db, "lmm");
  CHECK_FALSE(results.reference_lap_s.has_value());
  CHECK(results.baseline_note.find("gives no reference_lap_s") != std::string::npos);
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  CHECK_FALSE(report.mixed_model.has_value());
  CHECK(report.why_no_mixed_model.find("at least 2 participants, got 1") != std::string::npos);
  const ReportFiles files = WriteReport(results, report, dir / "out");
  CHECK(files.model_means_png.empty());
  // No reference lap: trials.csv's percentage is empty, every row.
  const std::string trials = Read(files.trials_csv);
  CHECK(trials.find(",flags,over_reference_percent\n") != std::string::npos);
  size_t rows = 0, empty = 0;
  for (size_t at = trials.find('\n'); at != std::string::npos && at + 1 < trials.size();
       at = trials.find('\n', at + 1)) {
    ++rows;
    if (trials[trials.find('\n', at + 1) - 1] == ',') ++empty;
  }
  CHECK(rows == one.size());
  CHECK(empty == rows);
  const std::string json = ReportJson(results, report, files);
  CHECK(json.find("\"lmm\":null,\"why_no_lmm\":\"no mixed model: ") != std::string::npos);
  CHECK(json.find("\"baseline\":{\"reference_lap_s\":null,\"why\":") != std::string::npos);
  const std::string text = FormatReport(results, report);
  CHECK(text.find("no mixed model: mixed model: expected at least 2 participants") !=
        std::string::npos);
}

TEST_CASE(
    "The report's mixed model leaves out a position that the order confounds with the condition") {
  // Every participant in the study file's order: position = condition + 1.
  const auto dir = test::ScratchDir("study-report-lmm-fixed");
  const auto db = dir / "fixed.db";
  std::vector<Lap> fixed = kBalanced;
  for (Lap& lap : fixed) lap.condition = lap.position - 1;
  Record(dir, db, fixed, "");
  const StudyReport report = ComputeReport(LoadStudyResults(db, "lmm"), PostHocMethod::kNemenyi);
  REQUIRE(report.mixed_model.has_value());
  CHECK_FALSE(report.mixed_model->position.has_value());
  const ReportFiles files = WriteReport(LoadStudyResults(db, "lmm"), report, dir / "out");
  const std::string json = ReportJson(LoadStudyResults(db, "lmm"), report, files);
  CHECK(json.find("\"position\":null") != std::string::npos);
  CHECK(json.find("position is left out") != std::string::npos);
}

TEST_CASE("The report says when Friedman's p is the chi-square approximation") {
  // 16 participants (the balanced set twice) and 4 conditions: past the exact
  // p's step limit (haptel/study/statistics.hpp), so the χ² p is the one used.
  const auto dir = test::ScratchDir("study-report-friedman-chi2");
  const auto db = dir / "lmm.db";
  std::vector<Lap> laps = kBalanced;
  for (Lap lap : kBalanced) {
    lap.participant += 8;
    laps.push_back(lap);
  }
  Record(dir, db, laps, "");
  const StudyResults results = LoadStudyResults(db, "lmm");
  const StudyReport report = ComputeReport(results, PostHocMethod::kNemenyi);
  REQUIRE(report.analysis.has_value());
  CHECK(report.analysis->friedman.participants == 16);
  CHECK_FALSE(report.analysis->friedman.p_exact);
  const std::string text = FormatReport(results, report);
  INFO(text.substr(text.find("  Friedman"), 160));
  CHECK(text.find(Fixed4(report.analysis->friedman.p_value_asymptotic) +
                  " (chi2 approximation);") != std::string::npos);
  const std::string json = ReportJson(results, report, WriteReport(results, report, dir / "out"));
  CHECK(json.find("\"friedman_p_exact\":false") != std::string::npos);
  CHECK(NumberAfter(json, "\"friedman_p\":") == NumberAfter(json, "\"friedman_p_asymptotic\":"));
}
