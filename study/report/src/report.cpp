#include "haptel/study/report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "haptel/core/html.hpp"
#include "haptel/core/json.hpp"
#include "haptel/record/sqlite_util.hpp"

namespace haptel::study {
namespace {

using namespace haptel::sql;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

std::string Fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

/// Whether `text` is a number as a whole ("-3", "+2.5", "1e3"): a cell a
/// spreadsheet reads as a value, never as a formula.
bool IsNumber(const std::string& text) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

/// A CSV field: quoted when it holds a comma, a quote or a line break. Free
/// text a spreadsheet would run as a formula (it begins with =, +, -, @, a
/// tab or a carriage return, and is not a number) is written after a single
/// quote, as OWASP advises against CSV injection: a participant's remark
/// "=HYPERLINK(...)" stays text on the experimenter's machine.
std::string Csv(const std::string& text) {
  const bool formula = !text.empty() &&
                       std::string("=+-@\t\r").find(text.front()) != std::string::npos &&
                       !IsNumber(text);
  if (formula) {
    std::string out = "\"'";
    for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
  }
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string Html(const std::string& text) { return HtmlEscape(text); }

std::string Ordinal(double rank) {
  if (std::abs(rank - std::round(rank)) > 1e-9) return Fixed(rank, 1);
  const int r = static_cast<int>(std::lround(rank));
  const char* suffix = r % 10 == 1 && r != 11   ? "st"
                       : r % 10 == 2 && r != 12 ? "nd"
                       : r % 10 == 3 && r != 13 ? "rd"
                                                : "th";
  return std::to_string(r) + suffix;
}

void WriteFile(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

bool IsNumber(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size() && std::isfinite(value);
}

/// A table cell's marks for `participant`'s trials of `condition`: "*" when
/// one stopped at the cap (scored at it), "!" when one has flags (something
/// could have spoiled it: trials.csv's flags column says what).
std::string Marks(const StudyResults& results, const std::string& participant,
                  const std::string& condition) {
  bool capped = false;
  bool flagged = false;
  for (const StudyResults::Trial& t : results.trials) {
    if (t.participant != participant || t.condition != condition) continue;
    capped = capped || !t.completed;
    flagged = flagged || !t.flags.empty();
  }
  return std::string(capped ? "*" : "") + (flagged ? "!" : "");
}

/// The flagged trials, one line each: who, what, and what could have spoiled it.
std::vector<std::string> FlaggedTrials(const StudyResults& results) {
  std::vector<std::string> lines;
  for (const StudyResults::Trial& t : results.trials) {
    if (t.flags.empty()) continue;
    lines.push_back(t.participant + ", " + t.condition + " (position " +
                    std::to_string(t.position) + ", run " + std::to_string(t.run_id) +
                    "): " + t.flags);
  }
  return lines;
}

/// The participants' background (the answers given about no condition: the
/// study's demographics questionnaire): per item, in the order first
/// answered, each value with how many participants gave it.
std::vector<std::pair<std::string, std::vector<std::pair<std::string, int>>>> Background(
    const StudyResults& results) {
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, int>>>> items;
  for (const StudyResults::Answer& a : results.answers) {
    if (!a.condition.empty()) continue;
    const std::string key = a.questionnaire + "." + a.item;
    auto item =
        std::find_if(items.begin(), items.end(), [&](const auto& i) { return i.first == key; });
    if (item == items.end()) item = items.insert(items.end(), {key, {}});
    auto value = std::find_if(item->second.begin(), item->second.end(),
                              [&](const auto& v) { return v.first == a.value; });
    if (value == item->second.end()) {
      item->second.push_back({a.value, 1});
    } else {
      ++value->second;
    }
  }
  return items;
}

/// One item's counts: "18-24 2, 25-34 1".
std::string Counts(const std::vector<std::pair<std::string, int>>& values) {
  std::string text;
  for (const auto& [value, n] : values)
    text += (text.empty() ? "" : ", ") + value + " " + std::to_string(n);
  return text;
}

/// The superseded trials, one line each: who, what, the lap as it was, why.
std::vector<std::string> SupersededTrials(const StudyResults& results) {
  std::vector<std::string> lines;
  for (const StudyResults::Superseded& s : results.superseded) {
    const StudyResults::Trial& t = s.trial;
    lines.push_back(t.participant + ", " + t.condition + " (position " +
                    std::to_string(t.position) + ", attempt " + std::to_string(t.attempt) +
                    ", run " + std::to_string(t.run_id) + "): " + Fixed(t.lap_time_s, 2) + " s" +
                    (t.completed ? "" : " (cap)") + "; " + s.why);
  }
  return lines;
}

/// Where a note belongs: "A, gesture (position 2)" or "A" for the participant.
std::string NotePlace(const StudyResults::Note& n) {
  if (n.position == 0) return n.participant;
  return n.participant + ", " + n.condition + " (position " + std::to_string(n.position) + ")";
}

/// A trial's columns in the order both the trials' and the superseded
/// trials' queries select them.
void ReadTrial(Reader& row, StudyResults::Trial& t) {
  t.participant = row.Text();
  t.position = static_cast<int>(row.Int());
  t.condition = row.Text();
  t.lap_time_s = row.Real();
  t.completed = row.Bool();
  t.obstacles = static_cast<int>(row.Int());
  t.run_id = row.Int();
  t.outcome = row.Text();
  t.attempt = static_cast<int>(row.Int());
  t.approach_s = row.Real();
  t.flags = row.Text();
  t.device = row.Text();
  t.session_file = row.Text();
  std::error_code ec;
  t.session_missing = !t.session_file.empty() && !std::filesystem::exists(t.session_file, ec);
}

/// The trials' session files, one line each ("" when no trial has one): a
/// file gone from the disk is said, never opened.
std::vector<std::string> SessionFiles(const StudyResults& results) {
  std::vector<std::string> lines;
  for (const StudyResults::Trial& t : results.trials) {
    if (t.session_file.empty()) continue;
    lines.push_back(t.participant + ", " + t.condition + " (position " +
                    std::to_string(t.position) + ", run " + std::to_string(t.run_id) + "): " +
                    t.session_file + (t.session_missing ? " (MISSING: deleted or moved)" : ""));
  }
  return lines;
}

/// The study named `name` in the database: its id (0: none), operators and cap.
int64_t FindStudy(const std::filesystem::path& database, sqlite3* raw, const std::string& name,
                  StudyResults& r) {
  int64_t id = 0;
  sqlite3_stmt* probe = nullptr;
  if (sqlite3_prepare_v2(raw, "SELECT id, operators, trial_cap_s FROM studies WHERE name = ?", -1,
                         &probe, nullptr) != SQLITE_OK) {
    sqlite3_finalize(probe);
    throw std::runtime_error("database " + database.string() + ": holds no studies (" +
                             sqlite3_errmsg(raw) + ")");
  }
  Stmt find(probe);
  Binder(database, raw, find.get()).Text(name);
  if (sqlite3_step(find.get()) == SQLITE_ROW) {
    Reader row(find.get());
    id = row.Int();
    r.operators = row.Text();
    r.trial_cap_s = row.Real();
  }
  return id;
}

/// The study's design: the baseline (the track's, read now: the reference
/// lap changes no trial), its conditions, participants and planned trials.
void ReadDesign(const std::filesystem::path& database, sqlite3* raw, int64_t id, StudyResults& r) {
  {
    Stmt form = Prepare(database, raw, "SELECT file, definition_form FROM studies WHERE id = ?",
                        "cannot read the study's definition");
    Binder(database, raw, form.get()).Int(id);
    if (sqlite3_step(form.get()) == SQLITE_ROW) {
      Reader row(form.get());
      const std::string file = row.Text();
      ReadBaseline(file, row.Text(), r);
    }
  }
  Stmt conditions = Prepare(
      database, raw, "SELECT name FROM study_conditions WHERE study_id = ? ORDER BY position",
      "cannot read the conditions");
  Binder(database, raw, conditions.get()).Int(id);
  while (sqlite3_step(conditions.get()) == SQLITE_ROW)
    r.conditions.push_back(Reader(conditions.get()).Text());
  Stmt participants =
      Prepare(database, raw,
              "SELECT participant FROM study_participants WHERE study_id = ? ORDER BY row_index",
              "cannot read the participants");
  Binder(database, raw, participants.get()).Int(id);
  while (sqlite3_step(participants.get()) == SQLITE_ROW)
    r.participants.push_back(Reader(participants.get()).Text());
  Stmt planned = Prepare(database, raw, "SELECT COUNT(*) FROM study_plan WHERE study_id = ?",
                         "cannot read the plan");
  Binder(database, raw, planned.get()).Int(id);
  if (sqlite3_step(planned.get()) == SQLITE_ROW)
    r.trials_planned = static_cast<int>(Reader(planned.get()).Int());
}

/// The trials, in the participants' order. Read-only, so not migrated: a
/// database from before v8 has neither the approach nor the flags (read as
/// unknown and none), one before v14 not the device ('').
void ReadTrials(const std::filesystem::path& database, sqlite3* raw, int64_t id, int version,
                StudyResults& r) {
  const std::string v8 = version >= 8 ? "t.approach_s, t.flags" : "NULL, ''";
  const std::string v14 = version >= 14 ? "t.device" : "''";
  const std::string v15 =
      version >= 15 ? "(SELECT session_file FROM runs WHERE id = t.run_id)" : "''";
  const std::string select_trials =
      "SELECT t.participant, t.position, t.condition, t.lap_time_s, t.completed, t.obstacles, "
      "t.run_id, t.outcome, "
      "t.attempt, " +
      v8 + ", " + v14 + ", " + v15 +
      " FROM study_trials t JOIN study_participants s ON s.study_id = t.study_id AND "
      "s.participant = t.participant WHERE t.study_id = ? ORDER BY s.row_index, t.position";
  Stmt trials = Prepare(database, raw, select_trials.c_str(), "cannot read the trials");
  Binder(database, raw, trials.get()).Int(id);
  while (sqlite3_step(trials.get()) == SQLITE_ROW) {
    Reader row(trials.get());
    StudyResults::Trial t;
    ReadTrial(row, t);
    r.trials.push_back(t);
  }
}

void ReadAnswers(const std::filesystem::path& database, sqlite3* raw, int64_t id, StudyResults& r) {
  Stmt answers =
      Prepare(database, raw,
              "SELECT participant, condition, questionnaire, item, value FROM study_answers WHERE "
              "study_id = ? ORDER BY rowid",
              "cannot read the answers");
  Binder(database, raw, answers.get()).Int(id);
  while (sqlite3_step(answers.get()) == SQLITE_ROW) {
    Reader row(answers.get());
    StudyResults::Answer a;
    a.participant = row.Text();
    a.condition = row.Text();
    a.questionnaire = row.Text();
    a.item = row.Text();
    a.value = row.Text();
    r.answers.push_back(a);
  }
}

/// The superseded trials and the experimenter's notes (schema v10).
void ReadSupersededAndNotes(const std::filesystem::path& database, sqlite3* raw, int64_t id,
                            int version, StudyResults& r) {
  const std::string select_superseded =
      std::string(
          "SELECT participant, position, condition, lap_time_s, completed, obstacles, run_id, "
          "outcome, attempt, approach_s, flags, ") +
      (version >= 14 ? "device" : "''") + ", " +
      (version >= 15 ? "(SELECT session_file FROM runs r WHERE r.id = run_id)" : "''") +
      ", why FROM study_superseded_trials WHERE study_id = ? ORDER BY id";
  Stmt superseded =
      Prepare(database, raw, select_superseded.c_str(), "cannot read the superseded trials");
  Binder(database, raw, superseded.get()).Int(id);
  while (sqlite3_step(superseded.get()) == SQLITE_ROW) {
    Reader row(superseded.get());
    StudyResults::Superseded s;
    ReadTrial(row, s.trial);
    s.why = row.Text();
    r.superseded.push_back(s);
  }
  Stmt notes = Prepare(
      database, raw,
      "SELECT n.participant, n.position, COALESCE(p.condition, ''), n.text, n.noted_utc FROM "
      "study_notes n LEFT JOIN study_plan p ON p.study_id = n.study_id AND p.participant = "
      "n.participant AND p.position = n.position WHERE n.study_id = ? ORDER BY n.id",
      "cannot read the notes");
  Binder(database, raw, notes.get()).Int(id);
  while (sqlite3_step(notes.get()) == SQLITE_ROW) {
    Reader row(notes.get());
    StudyResults::Note n;
    n.participant = row.Text();
    n.position = static_cast<int>(row.Int());
    n.condition = row.Text();
    n.text = row.Text();
    n.noted_utc = row.Text();
    r.notes.push_back(n);
  }
}

}  // namespace

StudyResults LoadStudyResults(const std::filesystem::path& database, const std::string& name) {
  if (!std::filesystem::is_regular_file(database)) {
    throw std::runtime_error("database " + database.string() +
                             ": no such file (run `haptel study run` first)");
  }
  sqlite3* raw = nullptr;
  if (sqlite3_open_v2(database.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string what = raw != nullptr ? sqlite3_errmsg(raw) : "cannot open";
    sqlite3_close_v2(raw);
    throw std::runtime_error("database " + database.string() + ": " + what);
  }
  const DbHandle db(raw);
  sqlite3_busy_timeout(raw, 2000);
  StudyResults r;
  r.database = database;
  r.name = name;
  const int64_t id = FindStudy(database, raw, name, r);
  if (id == 0) {
    Stmt all =
        Prepare(database, raw, "SELECT name FROM studies ORDER BY id", "cannot list the studies");
    std::string names;
    while (sqlite3_step(all.get()) == SQLITE_ROW)
      names += (names.empty() ? "" : ", ") + Reader(all.get()).Text();
    throw std::runtime_error("database " + database.string() + ": no study '" + name + "' (" +
                             (names.empty() ? "it holds none" : "it holds: " + names) + ")");
  }
  ReadDesign(database, raw, id, r);
  int version = 0;
  {
    Stmt pragma = Prepare(database, raw, "PRAGMA user_version", "cannot read the schema version");
    if (sqlite3_step(pragma.get()) == SQLITE_ROW)
      version = static_cast<int>(Reader(pragma.get()).Int());
  }
  ReadTrials(database, raw, id, version, r);
  ReadAnswers(database, raw, id, r);
  if (version >= 10) ReadSupersededAndNotes(database, raw, id, version, r);
  return r;
}

namespace {

/// A condition's mean and median lap time and mean rank, from its
/// participants' lap times and ranks.
void SummariseCondition(ConditionSummary& c) {
  std::vector<double> values;
  for (const double v : c.lap_time_s) {
    if (std::isfinite(v)) values.push_back(v);
  }
  c.mean_lap_time_s = values.empty() ? kNaN : c.total_lap_time_s / static_cast<double>(c.trials);
  c.median_lap_time_s = Median(values);
  double rank_sum = 0.0;
  int used = 0;
  for (const double r : c.rank) {
    if (std::isfinite(r)) {
      rank_sum += r;
      ++used;
    }
  }
  c.mean_rank = used > 0 ? rank_sum / used : kNaN;
}

/// Numeric questionnaire answers, per questionnaire × item × condition.
std::vector<ItemSummary> SummariseItems(const StudyResults& results) {
  std::vector<ItemSummary> summaries;
  std::map<std::tuple<std::string, std::string, std::string>, std::vector<double>> numeric;
  for (const StudyResults::Answer& a : results.answers) {
    double value = 0.0;
    // The participants' background (no condition) is counted apart (Background).
    if (!a.condition.empty() && IsNumber(a.value, value)) {
      numeric[{a.questionnaire, a.item, a.condition}].push_back(value);
    }
  }
  for (const auto& [key, values] : numeric) {
    ItemSummary s;
    std::tie(s.questionnaire, s.item, s.condition) = key;
    s.n = static_cast<int>(values.size());
    double sum = 0.0;
    for (const double v : values) sum += v;
    s.mean = sum / s.n;
    s.median = Median(values);
    s.min = *std::min_element(values.begin(), values.end());
    s.max = *std::max_element(values.begin(), values.end());
    summaries.push_back(s);
  }
  return summaries;
}

}  // namespace

StudyReport ComputeReport(const StudyResults& results, PostHocMethod post_hoc, double alpha) {
  StudyReport report;
  const size_t k = results.conditions.size();
  const size_t n = results.participants.size();
  // Mean scored lap time per participant and condition (over repetitions).
  std::vector<std::vector<std::vector<double>>> laps(n, std::vector<std::vector<double>>(k));
  std::vector<std::vector<int>> obstacles(n, std::vector<int>(k, 0));
  for (size_t c = 0; c < k; ++c) {
    ConditionSummary summary;
    summary.name = results.conditions[c];
    report.conditions.push_back(summary);
  }
  for (const StudyResults::Trial& t : results.trials) {
    const auto p =
        std::find(results.participants.begin(), results.participants.end(), t.participant);
    const auto c = std::find(results.conditions.begin(), results.conditions.end(), t.condition);
    if (p == results.participants.end() || c == results.conditions.end()) continue;
    const size_t pi = static_cast<size_t>(p - results.participants.begin());
    const size_t ci = static_cast<size_t>(c - results.conditions.begin());
    laps[pi][ci].push_back(t.lap_time_s);
    obstacles[pi][ci] += t.obstacles;
    report.conditions[ci].trials += 1;
    report.conditions[ci].unfinished += t.completed ? 0 : 1;
    report.conditions[ci].total_lap_time_s += t.lap_time_s;
    report.conditions[ci].total_obstacles += t.obstacles;
  }
  BlockMatrix matrix;
  for (size_t p = 0; p < n; ++p) {
    std::vector<double> row(k, kNaN);
    bool complete = true;
    for (size_t c = 0; c < k; ++c) {
      if (laps[p][c].empty()) {
        complete = false;
        continue;
      }
      double sum = 0.0;
      for (const double v : laps[p][c]) sum += v;
      row[c] = sum / static_cast<double>(laps[p][c].size());
    }
    std::vector<double> ranks(k, kNaN);
    if (complete) {
      ranks = Ranks(row);
      matrix.push_back(row);
      report.participants_used.push_back(results.participants[p]);
    }
    for (size_t c = 0; c < k; ++c) {
      report.conditions[c].lap_time_s.push_back(row[c]);
      report.conditions[c].rank.push_back(ranks[c]);
      report.conditions[c].obstacles.push_back(obstacles[p][c]);
    }
  }
  for (ConditionSummary& c : report.conditions) SummariseCondition(c);
  if (matrix.size() < 2) {
    report.why_no_statistics =
        "the statistics need at least 2 participants with a trial in every condition (" +
        std::to_string(matrix.size()) + " so far)";
  } else {
    try {
      report.analysis = AnalyzeWithinSubject(matrix, post_hoc, alpha);
    } catch (const std::invalid_argument& e) {
      report.why_no_statistics = std::string("no statistics: ") + e.what();
    }
  }
  FitLapTimeModel(results, report);
  report.items = SummariseItems(results);
  return report;
}

std::string FormatReport(const StudyResults& results, const StudyReport& report) {
  std::ostringstream o;
  o << "study " << results.name << ": " << results.trials.size() << " of " << results.trials_planned
    << " trials, " << results.participants.size() << " participants, " << results.conditions.size()
    << " conditions (lap times in s as scored, on the lap's clock from the start line; unfinished "
       "laps count "
       "as the "
    << Fixed(results.trial_cap_s, 0)
    << " s cap, on the same clock; the approach before the line is trials.csv's approach_s, not "
       "scored)\n";
  for (const ConditionSummary& c : report.conditions) {
    o << "\n  " << c.name << "\n    " << std::string(10, ' ');
    for (const std::string& p : results.participants)
      o << " " << std::string(std::max<int>(0, 8 - static_cast<int>(p.size())), ' ') << p;
    o << "\n    Time      ";
    for (size_t p = 0; p < c.lap_time_s.size(); ++p) {
      const std::string text =
          Fixed(c.lap_time_s[p], 2) + Marks(results, results.participants[p], c.name);
      o << " " << std::string(std::max(0, 8 - static_cast<int>(text.size())), ' ') << text;
    }
    o << "\n    Rank      ";
    for (const double r : c.rank) {
      const std::string text = std::isfinite(r) ? Ordinal(r) : "-";
      o << " " << std::string(std::max(0, 8 - static_cast<int>(text.size())), ' ') << text;
    }
    o << "\n    Obstacles ";
    for (const int v : c.obstacles)
      o << " " << std::string(std::max(0, 8 - static_cast<int>(std::to_string(v).size())), ' ')
        << v;
    o << "\n    total " << Fixed(c.total_lap_time_s, 2) << " s, mean "
      << Fixed(c.mean_lap_time_s, 2) << " s, median " << Fixed(c.median_lap_time_s, 2)
      << " s, mean rank " << Fixed(c.mean_rank, 2) << ", obstacles " << c.total_obstacles
      << (c.unfinished > 0 ? ", unfinished " + std::to_string(c.unfinished) : "") << "\n";
  }
  o << "\n  (* capped: scored at the cap; ! flagged: something could have spoiled the trial)\n";
  const std::vector<std::string> flagged = FlaggedTrials(results);
  if (!flagged.empty()) {
    o << "  flagged trials (scored like the others; a redo runs one again):\n";
    for (const std::string& line : flagged) o << "    " << line << "\n";
  }
  if (const std::vector<std::string> superseded = SupersededTrials(results); !superseded.empty()) {
    o << "  superseded trials (run again; only the latest attempt is counted):\n";
    for (const std::string& line : superseded) o << "    " << line << "\n";
  }
  if (const std::vector<std::string> files = SessionFiles(results); !files.empty()) {
    o << "  session files (each trial whole: open in Foxglove or Lichtblick, or haptel replay):\n";
    for (const std::string& line : files) o << "    " << line << "\n";
  }
  o << "\n";
  if (!report.analysis) {
    o << "  " << report.why_no_statistics << "\n";
  } else {
    const WithinSubjectAnalysis& a = *report.analysis;
    // Which p it is: with few participants the χ² approximation can be far
    // off (k = 2, N = 4 all one way: 0.046 against the exact 0.125).
    const std::string p_kind =
        a.friedman.p_exact ? "exact; chi2 approximation " + Fixed(a.friedman.p_value_asymptotic, 4)
                           : "chi2 approximation";
    o << "  Friedman: chi2 = " << Fixed(a.friedman.chi_square, 3)
      << ", df = " << a.friedman.degrees_of_freedom << ", p = " << Fixed(a.friedman.p_value, 4)
      << " (" << p_kind << "); Kendall's W = " << Fixed(a.friedman.kendall_w, 3)
      << " (N = " << a.friedman.participants << ", k = " << a.friedman.conditions << ")\n";
    o << "  post-hoc: " << a.post_hoc.method;
    if (!a.post_hoc.pairs.empty() && a.post_hoc.pairs[0].critical_difference) {
      o << ", critical difference " << Fixed(*a.post_hoc.pairs[0].critical_difference, 3)
        << " (mean ranks)";
    }
    o << "\n";
    for (const PairComparison& pair : a.post_hoc.pairs) {
      o << "    " << report.conditions[static_cast<size_t>(pair.condition_a)].name << " vs "
        << report.conditions[static_cast<size_t>(pair.condition_b)].name << ": "
        << Fixed(pair.statistic, 3);
      if (pair.p_value) o << ", p = " << Fixed(*pair.p_value, 4);
      o << (pair.significant ? "  significant" : "") << "\n";
    }
  }
  o << "\n" << FormatLapTimeModel(results, report) << "\n" << FormatBaseline(results, report);
  if (!report.items.empty()) {
    o << "\n  questionnaires (mean, median, n):\n";
    for (const ItemSummary& s : report.items) {
      o << "    " << s.questionnaire << "." << s.item << " " << s.condition << ": "
        << Fixed(s.mean, 2) << ", " << Fixed(s.median, 2) << ", " << s.n << "\n";
    }
  }
  if (const auto background = Background(results); !background.empty()) {
    o << "\n  participants' background (demographics.csv; answers and how many gave each):\n";
    for (const auto& [item, values] : background)
      o << "    " << item << ": " << Counts(values) << "\n";
  }
  if (!results.notes.empty()) {
    o << "\n  the experimenter's notes (notes.csv):\n";
    for (const StudyResults::Note& n : results.notes)
      o << "    " << NotePlace(n) << ": " << n.text << "\n";
  }
  return o.str();
}

namespace {

/// trials.csv: a row per trial, with its lap against the track's reference.
std::string TrialsCsv(const StudyResults& results) {
  std::string trials =
      "study,participant,condition,device,position,lap_time_s,approach_s,completed,obstacles,"
      "run_id,"
      "outcome,attempt,"
      "flags,over_reference_percent\n";
  for (const StudyResults::Trial& t : results.trials) {
    // The lap against the track's reference lap, as the report's baseline
    // table shows it (empty when the track gives none).
    const std::string over_reference =
        results.reference_lap_s
            ? Fixed(PercentOverReference(t.lap_time_s, *results.reference_lap_s), 2)
            : "";
    trials += Csv(results.name) + "," + Csv(t.participant) + "," + Csv(t.condition) + "," +
              Csv(t.device) + "," + std::to_string(t.position) + "," + Fixed(t.lap_time_s, 3) +
              "," + (std::isfinite(t.approach_s) ? Fixed(t.approach_s, 3) : std::string()) + "," +
              (t.completed ? "true" : "false") + "," + std::to_string(t.obstacles) + "," +
              std::to_string(t.run_id) + "," + Csv(t.outcome) + "," + std::to_string(t.attempt) +
              "," + Csv(t.flags) + "," + over_reference + "\n";
  }
  return trials;
}

/// answers.csv: a row per questionnaire item answered.
std::string AnswersCsv(const StudyResults& results) {
  std::string answers = "study,participant,condition,questionnaire,item,value\n";
  for (const StudyResults::Answer& a : results.answers) {
    answers += Csv(results.name) + "," + Csv(a.participant) + "," + Csv(a.condition) + "," +
               Csv(a.questionnaire) + "," + Csv(a.item) + "," + Csv(a.value) + "\n";
  }
  return answers;
}

/// notes.csv: the experimenter's notes.
std::string NotesCsv(const StudyResults& results) {
  std::string notes = "study,participant,position,condition,noted_utc,text\n";
  for (const StudyResults::Note& n : results.notes) {
    notes += Csv(results.name) + "," + Csv(n.participant) + "," + std::to_string(n.position) + "," +
             Csv(n.condition) + "," + Csv(n.noted_utc) + "," + Csv(n.text) + "\n";
  }
  return notes;
}

/// demographics.csv: the background one row per participant (a paper's
/// participants table), one column per item in the order first answered.
std::string DemographicsCsv(const StudyResults& results) {
  std::vector<std::string> columns;
  std::map<std::string, std::map<std::string, std::string>> by_participant;
  for (const StudyResults::Answer& a : results.answers) {
    if (!a.condition.empty()) continue;
    if (std::find(columns.begin(), columns.end(), a.item) == columns.end())
      columns.push_back(a.item);
    by_participant[a.participant][a.item] = a.value;
  }
  std::string demographics = "study,participant";
  for (const std::string& c : columns) {
    demographics += ',';
    demographics += Csv(c);
  }
  demographics += "\n";
  for (const std::string& p : results.participants) {
    const auto row = by_participant.find(p);
    if (row == by_participant.end()) continue;
    demographics += Csv(results.name) + "," + Csv(p);
    for (const std::string& c : columns) {
      const auto value = row->second.find(c);
      demographics += ',';  // appended apart: GCC 12 warns falsely (-Wrestrict) on "," + string
      if (value != row->second.end()) demographics += Csv(value->second);
    }
    demographics += "\n";
  }
  return demographics;
}

/// summary.csv: a row per condition.
std::string SummaryCsv(const StudyResults& results, const StudyReport& report) {
  std::string summary =
      "study,condition,trials,unfinished,total_lap_time_s,mean_lap_time_s,median_lap_time_s,mean_"
      "rank,obstacles\n";
  for (const ConditionSummary& c : report.conditions) {
    summary += Csv(results.name) + "," + Csv(c.name) + "," + std::to_string(c.trials) + "," +
               std::to_string(c.unfinished) + "," + Fixed(c.total_lap_time_s, 3) + "," +
               Fixed(c.mean_lap_time_s, 3) + "," + Fixed(c.median_lap_time_s, 3) + "," +
               Fixed(c.mean_rank, 3) + "," + std::to_string(c.total_obstacles) + "\n";
  }
  return summary;
}

/// index.html: the thesis's tables, the statistics, the questionnaires, the
/// plots `files` holds.
std::string ReportPage(const StudyResults& results, const StudyReport& report,
                       const ReportFiles& files) {
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Study " << Html(results.name)
    << "</"
       "title>\n<style>body{font-family:sans-serif;margin:2em;max-width:70em}table{border-collapse:"
       "collapse;"
       "margin:0.5em 0 1.5em}td,th{border:1px solid #999;padding:0.2em 0.6em;text-align:right}"
       "th{background:#eee}caption{text-align:left;font-weight:bold}</style></head><body>\n";
  h << "<h1>Study " << Html(results.name) << "</h1>\n<p>" << results.trials.size() << " of "
    << results.trials_planned
    << " trials; lap times in seconds as scored, on the lap's clock: from the start line to the "
       "finish (an "
       "unfinished lap counts as the "
    << Fixed(results.trial_cap_s, 0)
    << " s cap, on the same clock, whatever the interface). The time before the line (the "
       "approach, a "
       "cockpit's grasp of its controls) is kept apart as <code>approach_s</code> in trials.csv "
       "and not "
       "scored.</p>\n";
  for (const ConditionSummary& c : report.conditions) {
    h << "<table><caption>" << Html(c.name) << "</caption><tr><th>People</th>";
    for (const std::string& p : results.participants) h << "<th>" << Html(p) << "</th>";
    h << "<th>total</th></tr>\n<tr><th>Time</th>";
    for (size_t p = 0; p < c.lap_time_s.size(); ++p) {
      h << "<td>" << Fixed(c.lap_time_s[p], 2)
        << Html(Marks(results, results.participants[p], c.name)) << "</td>";
    }
    h << "<td>" << Fixed(c.total_lap_time_s, 2) << "</td></tr>\n<tr><th>Rank</th>";
    for (const double r : c.rank) h << "<td>" << (std::isfinite(r) ? Ordinal(r) : "-") << "</td>";
    h << "<td>mean " << Fixed(c.mean_rank, 2) << "</td></tr>\n<tr><th>Obstacles</th>";
    for (const int v : c.obstacles) h << "<td>" << v << "</td>";
    h << "<td>" << c.total_obstacles << "</td></tr></table>\n";
  }
  h << "<p>* capped: scored at the cap. ! flagged: something could have spoiled the trial.</p>\n";
  if (const std::vector<std::string> flagged = FlaggedTrials(results); !flagged.empty()) {
    h << "<h2>Flagged trials</h2>\n<p>Scored like the others; the console's redo runs one "
         "again.</p>\n<ul>\n";
    for (const std::string& line : flagged) h << "<li>" << Html(line) << "</li>\n";
    h << "</ul>\n";
  }
  if (const std::vector<std::string> superseded = SupersededTrials(results); !superseded.empty()) {
    h << "<h2>Superseded trials</h2>\n<p>Run again; only the latest attempt is counted above.</p>\n"
         "<ul id=\"superseded\">\n";
    for (const std::string& line : superseded) h << "<li>" << Html(line) << "</li>\n";
    h << "</ul>\n";
  }
  if (std::any_of(results.trials.begin(), results.trials.end(),
                  [](const StudyResults::Trial& t) { return !t.session_file.empty(); })) {
    h << "<h2>Session files</h2>\n<p>Each trial whole (MCAP): open it in Foxglove or Lichtblick, "
         "or play it with <code>haptel replay</code>.</p>\n<ul id=\"sessions\">\n";
    for (const StudyResults::Trial& t : results.trials) {
      if (t.session_file.empty()) continue;
      h << "<li>"
        << Html(t.participant + ", " + t.condition + " (position " + std::to_string(t.position) +
                "): ");
      if (t.session_missing) {
        h << Html(t.session_file) << " <strong>missing</strong> (deleted or moved)";
      } else {
        std::error_code ec;
        const std::filesystem::path absolute = std::filesystem::absolute(t.session_file, ec);
        const std::string url = "file://" + (ec ? t.session_file : absolute.string());
        h << "<a href=\"" << Html(url) << "\">" << Html(t.session_file) << "</a>";
      }
      h << "</li>\n";
    }
    h << "</ul>\n";
  }
  h << "<h2>Statistics</h2>\n<pre>";
  std::string text = FormatReport(results, report);
  // The background and the notes have their own lists below.
  for (const char* own : {"\n  participants' background", "\n  the experimenter's notes"}) {
    if (const size_t at = text.find(own); at != std::string::npos) text.resize(at + 1);
  }
  const size_t at = text.find("  Friedman");
  h << Html(at != std::string::npos
                ? text.substr(at)
                : report.why_no_statistics + "\n\n" + FormatLapTimeModel(results, report) + "\n" +
                      FormatBaseline(results, report))
    << "</pre>\n";
  bool remarks = false;
  for (const StudyResults::Answer& a : results.answers) {
    double value = 0.0;
    if (a.condition.empty() || IsNumber(a.value, value) ||
        a.item.find(".path") != std::string::npos)
      continue;
    if (!remarks) h << "<h2>Remarks</h2>\n<ul>\n";
    remarks = true;
    h << "<li>" << Html(a.participant) << ", " << Html(a.condition) << " (" << Html(a.questionnaire)
      << "." << Html(a.item) << "): " << Html(a.value) << "</li>\n";
  }
  if (remarks) h << "</ul>\n";
  if (const auto background = Background(results); !background.empty()) {
    h << "<h2>Participants' background</h2>\n<ul id=\"background\">\n";
    for (const auto& [item, values] : background)
      h << "<li>" << Html(item) << ": " << Html(Counts(values)) << "</li>\n";
    h << "</ul>\n";
  }
  if (!results.notes.empty()) {
    h << "<h2>The experimenter's notes</h2>\n<ul id=\"notes\">\n";
    for (const StudyResults::Note& n : results.notes) {
      h << "<li>" << Html(NotePlace(n)) << ": " << Html(n.text) << "</li>\n";
    }
    h << "</ul>\n";
  }
  h << "<h2>Plots</h2>\n<p><img src=\"lap_times.png\" alt=\"lap times per condition\"></p>\n"
    << "<p><img src=\"ranks.png\" alt=\"mean ranks per condition\"></p>\n";
  if (!files.ratings_png.empty())
    h << "<p><img src=\"ratings.png\" alt=\"questionnaire scores\"></p>\n";
  if (!files.model_means_png.empty()) {
    h << "<p><img src=\"model_means.png\" alt=\"the mixed model's estimated mean lap time per "
         "condition\"></p>\n";
  }
  h << "<p>Data: <a href=\"trials.csv\">trials.csv</a>, <a href=\"answers.csv\">answers.csv</a>, "
       "<a href=\"summary.csv\">summary.csv</a>, <a href=\"notes.csv\">notes.csv</a>, <a "
       "href=\"demographics.csv\">demographics.csv</a>.</p>\n</body></html>\n";
  return h.str();
}

}  // namespace

ReportFiles WriteReport(const StudyResults& results, const StudyReport& report,
                        const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  ReportFiles files;
  files.trials_csv = dir / "trials.csv";
  files.answers_csv = dir / "answers.csv";
  files.summary_csv = dir / "summary.csv";
  files.notes_csv = dir / "notes.csv";
  files.demographics_csv = dir / "demographics.csv";
  files.lap_times_png = dir / "lap_times.png";
  files.ranks_png = dir / "ranks.png";
  files.html = dir / "index.html";
  WriteFile(files.trials_csv, TrialsCsv(results));
  WriteFile(files.answers_csv, AnswersCsv(results));
  WriteFile(files.notes_csv, NotesCsv(results));
  WriteFile(files.demographics_csv, DemographicsCsv(results));
  WriteFile(files.summary_csv, SummaryCsv(results, report));
  DrawLapTimes(results, report, files.lap_times_png);
  DrawRanks(report, files.ranks_png);
  if (DrawRatings(results, dir / "ratings.png")) files.ratings_png = dir / "ratings.png";
  if (DrawModelMeans(results, report, dir / "model_means.png"))
    files.model_means_png = dir / "model_means.png";
  WriteFile(files.html, ReportPage(results, report, files));
  return files;
}

std::string ReportJson(const StudyResults& results, const StudyReport& report,
                       const ReportFiles& files) {
  auto number = [](double v) { return std::isfinite(v) ? JsonNumber(v) : std::string("null"); };
  std::string out = "{\"study\":" + JsonString(results.name) +
                    ",\"trials\":" + std::to_string(results.trials.size()) +
                    ",\"trials_planned\":" + std::to_string(results.trials_planned) +
                    ",\"participants_used\":" + std::to_string(report.participants_used.size()) +
                    ",\"conditions\":[";
  for (size_t i = 0; i < report.conditions.size(); ++i) {
    const ConditionSummary& c = report.conditions[i];
    if (i > 0) out += ",";
    out += "{\"name\":" + JsonString(c.name) +
           ",\"total_lap_time_s\":" + number(c.total_lap_time_s) +
           ",\"mean_lap_time_s\":" + number(c.mean_lap_time_s) +
           ",\"mean_rank\":" + number(c.mean_rank) +
           ",\"obstacles\":" + std::to_string(c.total_obstacles) + "}";
  }
  out += "]";
  if (report.analysis) {
    const WithinSubjectAnalysis& a = *report.analysis;
    out += ",\"friedman_chi2\":" + number(a.friedman.chi_square) +
           ",\"friedman_df\":" + std::to_string(a.friedman.degrees_of_freedom) +
           ",\"friedman_p\":" + number(a.friedman.p_value) +
           ",\"friedman_p_exact\":" + (a.friedman.p_exact ? "true" : "false") +
           ",\"friedman_p_asymptotic\":" + number(a.friedman.p_value_asymptotic) +
           ",\"kendall_w\":" + number(a.friedman.kendall_w) +
           ",\"post_hoc\":{\"method\":" + JsonString(a.post_hoc.method) +
           ",\"alpha\":" + number(a.post_hoc.alpha) + ",\"pairs\":[";
    for (size_t i = 0; i < a.post_hoc.pairs.size(); ++i) {
      const PairComparison& p = a.post_hoc.pairs[i];
      if (i > 0) out += ",";
      out += "{\"a\":" + JsonString(report.conditions[static_cast<size_t>(p.condition_a)].name) +
             ",\"b\":" + JsonString(report.conditions[static_cast<size_t>(p.condition_b)].name) +
             ",\"statistic\":" + number(p.statistic) + ",\"critical_difference\":" +
             (p.critical_difference ? number(*p.critical_difference) : "null") +
             ",\"p\":" + (p.p_value ? number(*p.p_value) : "null") +
             ",\"significant\":" + (p.significant ? "true" : "false") + "}";
    }
    out += "]}";
  } else {
    out +=
        ",\"friedman_chi2\":null,\"friedman_df\":null,\"friedman_p\":null,\"friedman_p_exact\":"
        "null,\"friedman_p_asymptotic\":null,\"kendall_w\":null,\"post_hoc\":null";
  }
  out += ",\"why_no_statistics\":" + JsonString(report.why_no_statistics);
  out += ",\"experimenter_notes\":" + std::to_string(results.notes.size());
  out += ",\"superseded_trials\":" + std::to_string(results.superseded.size());
  out += "," + LapTimeModelJson(results, report) + "," + BaselineJson(results, report);
  out += ",\"files\":{\"html\":" + JsonString(files.html.string()) +
         ",\"trials_csv\":" + JsonString(files.trials_csv.string()) +
         ",\"answers_csv\":" + JsonString(files.answers_csv.string()) +
         ",\"summary_csv\":" + JsonString(files.summary_csv.string()) +
         ",\"notes_csv\":" + JsonString(files.notes_csv.string()) +
         ",\"demographics_csv\":" + JsonString(files.demographics_csv.string()) +
         ",\"lap_times_png\":" + JsonString(files.lap_times_png.string()) +
         ",\"ranks_png\":" + JsonString(files.ranks_png.string()) +
         ",\"ratings_png\":" + JsonString(files.ratings_png.string()) +
         ",\"model_means_png\":" + JsonString(files.model_means_png.string()) + "}}";
  return out;
}

}  // namespace haptel::study
