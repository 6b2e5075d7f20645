#pragma once
/// @file The report on a study: the thesis's tables (per condition: each
/// participant's lap time as scored, their rank of the condition, obstacles)
/// with totals, the Friedman test, Kendall's W and a post-hoc test, the
/// questionnaires' summaries; written as CSV (long format, for R or pandas),
/// PNG plots and one HTML page, and printed.
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "haptel/study/mixed_model.hpp"
#include "haptel/study/power.hpp"
#include "haptel/study/statistics.hpp"

namespace haptel::study {

/// A study as recorded, read from the run database (read-only).
struct StudyResults {
  std::filesystem::path database;
  std::string name;
  std::string operators;
  double trial_cap_s = 0.0;
  std::vector<std::string> conditions;    ///< in the study file's order
  std::vector<std::string> participants;  ///< in the order they were added
  int trials_planned = 0;
  struct Trial {
    std::string participant;
    int position = 0;
    std::string condition;
    double lap_time_s = 0.0;  ///< as scored on the lap's clock (an unfinished lap: the cap)
    /// Before the lap's clock started (approach, a cockpit's grasp); not
    /// scored. NaN: recorded before the database kept it.
    double approach_s = std::numeric_limits<double>::quiet_NaN();
    bool completed = false;
    int obstacles = 0;
    int64_t run_id = 0;
    std::string outcome;
    int attempt = 1;
    /// What could have spoiled the trial (store.hpp TrialFlags); "": nothing.
    std::string flags;
    /// The input device it was driven with (its device file's name); "":
    /// recorded before the database kept it (schema v14).
    std::string device{};
    /// The trial's session file (MCAP; "": none, or recorded before the
    /// database kept it, schema v15), and whether it is gone from the disk
    /// now (deleted or moved): the report says so.
    std::string session_file{};
    bool session_missing = false;
  };
  std::vector<Trial> trials;  ///< the latest attempt of each trial: what is counted
  /// Trials taken back to be run again (a redo; a synthetic study's flagged
  /// trial run again once), as they were, with why: listed, not counted.
  struct Superseded {
    Trial trial;
    std::string why;
  };
  std::vector<Superseded> superseded;
  struct Answer {
    std::string participant;
    std::string condition;
    std::string questionnaire;
    std::string item;
    std::string value;
  };
  std::vector<Answer> answers;
  /// The experimenter's notes (schema v10; none before), in the order written.
  struct Note {
    std::string participant;
    int position = 0;       ///< 0: on the participant as a whole
    std::string condition;  ///< the planned trial's ("" for position 0)
    std::string text;
    std::string noted_utc;
  };
  std::vector<Note> notes;
  /// The baseline: the study's track's reference_lap_s (read from the track
  /// file the study's definition names, when the report is made: it changes
  /// no trial), or nullopt with `baseline_note` saying why.
  std::optional<double> reference_lap_s;
  std::filesystem::path track_file;
  std::string baseline_note;
};

/// Reads study `name`. Throws std::runtime_error with one line: no such
/// database, or no such study (listing the studies there).
StudyResults LoadStudyResults(const std::filesystem::path& database, const std::string& name);

/// One condition's row of the report.
struct ConditionSummary {
  std::string name;
  /// Per participant (StudyResults::participants order): mean scored lap
  /// time over repetitions, rank among the conditions (1 fastest, ties
  /// averaged), obstacles; NaN / 0 where the participant has no trial.
  std::vector<double> lap_time_s;
  std::vector<double> rank;
  std::vector<int> obstacles;
  double total_lap_time_s = 0.0;
  double mean_lap_time_s = 0.0;
  double median_lap_time_s = 0.0;
  double mean_rank = 0.0;  ///< over the participants used in the statistics
  int total_obstacles = 0;
  int trials = 0;
  int unfinished = 0;
};

/// A numeric questionnaire item's answers for one condition.
struct ItemSummary {
  std::string questionnaire;
  std::string item;
  std::string condition;
  int n = 0;
  double mean = 0.0;
  double median = 0.0;
  double min = 0.0;
  double max = 0.0;
};

struct StudyReport {
  std::vector<ConditionSummary> conditions;
  /// Participants with a trial in every condition: the statistics' rows.
  std::vector<std::string> participants_used;
  /// The statistics (nullopt with fewer than 2 participants used; `why` says so).
  std::optional<WithinSubjectAnalysis> analysis;
  std::string why_no_statistics;
  std::vector<ItemSummary> items;
  /// log(lap time) ~ condition + position + (1 | participant) over every
  /// trial as scored (report_model.cpp); reference: the study file's first
  /// condition. nullopt when it cannot be fitted, `why_no_mixed_model` says why.
  std::optional<MixedModelResult> mixed_model;
  std::string why_no_mixed_model;
};

/// Tables, ranks and statistics from the results.
StudyReport ComputeReport(const StudyResults& results, PostHocMethod post_hoc, double alpha = 0.05);

/// Files written into a folder.
struct ReportFiles {
  std::filesystem::path html, trials_csv, answers_csv, summary_csv, notes_csv, demographics_csv,
      lap_times_png, ranks_png, ratings_png, model_means_png;
};

/// Writes trials.csv, answers.csv, summary.csv, notes.csv (the
/// experimenter's notes; free text escaped as answers.csv's),
/// demographics.csv (the participants' background, the answers given about
/// no condition: one row per participant), lap_times.png, ranks.png,
/// ratings.png (when there are scored questionnaires) and index.html into
/// `dir` (created). Throws std::runtime_error naming a file it cannot write.
ReportFiles WriteReport(const StudyResults& results, const StudyReport& report,
                        const std::filesystem::path& dir);

/// The tables (one block per condition, participants as columns, as the
/// thesis's tables 8.1–8.4) and the statistics, readable.
std::string FormatReport(const StudyResults& results, const StudyReport& report);
/// One JSON line (no newline).
std::string ReportJson(const StudyResults& results, const StudyReport& report,
                       const ReportFiles& files);

/// Draws the plots (report_plots.cpp).
void DrawLapTimes(const StudyResults& results, const StudyReport& report,
                  const std::filesystem::path& png);
void DrawRanks(const StudyReport& report, const std::filesystem::path& png);
/// The power curve's legend: the tests power.hpp runs, as they are named in
/// the plot (the mixed model's is Satterthwaite's F test of the condition).
inline constexpr const char* kPowerFriedmanLegend = "Friedman";
inline constexpr const char* kPowerMixedModelLegend = "mixed model (Satterthwaite's F)";
/// `haptel study power`'s curve: each test's power per participant count
/// with its 95 % interval, and the target as a dashed line. Throws
/// std::runtime_error naming the file when it cannot be written.
void DrawPowerCurve(const PowerResult& power, const std::string& title,
                    const std::filesystem::path& png);
/// Returns false (and writes nothing) when no answer is a questionnaire's score.
bool DrawRatings(const StudyResults& results, const std::filesystem::path& png);
/// The mixed model's estimated mean lap time per condition (back-transformed
/// to s) with its 95 % interval, and the reference lap when there is one.
/// Returns false (and writes nothing) without a fitted model.
bool DrawModelMeans(const StudyResults& results, const StudyReport& report,
                    const std::filesystem::path& png);

/// The mixed model and the baseline in the report (report_model.cpp).
/// Fits report.mixed_model from the results' trials, or says why not.
void FitLapTimeModel(const StudyResults& results, StudyReport& report);
/// Sets results.reference_lap_s from the track named in the study's
/// definition form ("track: PATH", relative to the study file's folder).
void ReadBaseline(const std::filesystem::path& study_file, const std::string& definition_form,
                  StudyResults& results);
/// The text report's blocks: the model's table; each lap against the baseline.
std::string FormatLapTimeModel(const StudyResults& results, const StudyReport& report);
std::string FormatBaseline(const StudyResults& results, const StudyReport& report);
/// The JSON fields `"lmm":...,"why_no_lmm":...,"baseline":...`, to follow a comma.
std::string LapTimeModelJson(const StudyResults& results, const StudyReport& report);
std::string BaselineJson(const StudyResults& results, const StudyReport& report);
/// A lap's percentage over the reference lap: 100 (lap − reference)/reference.
double PercentOverReference(double lap_time_s, double reference_lap_s);

}  // namespace haptel::study
