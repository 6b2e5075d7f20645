#include "haptel/study/store.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "haptel/core/clock.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/record/sqlite_util.hpp"
#include "haptel/study/definition.hpp"

namespace haptel::study {
namespace {

using namespace haptel::sql;

std::string NowUtc() { return IsoUtc(WallNs()); }

std::string FileText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string Describe(const PlannedTrial& t) {
  return t.participant + " #" + std::to_string(t.position) + " " + t.condition;
}

/// Planned trials' rows (a new study's, or a participant's added later).
void InsertPlan(const std::filesystem::path& file, sqlite3* db, int64_t study,
                const std::vector<PlannedTrial>& plan) {
  Stmt planned = Prepare(file, db,
                         "INSERT INTO study_plan (study_id, participant, position, condition, "
                         "repetition, device) VALUES (?, ?, ?, ?, ?, ?)",
                         "cannot insert the plan");
  for (const PlannedTrial& t : plan) {
    sqlite3_reset(planned.get());
    Binder(file, db, planned.get())
        .Int(study)
        .Text(t.participant)
        .Int(t.position)
        .Text(t.condition)
        .Int(t.repetition)
        .Text(t.device);
    StepDone(file, db, planned.get(), "cannot insert planned trial " + Describe(t));
  }
}

/// A new study's rows: the study with its definition, its conditions, the
/// file's participants and the plan. Returns its id.
int64_t InsertStudy(const std::filesystem::path& file, sqlite3* db, const StudyConfig& config,
                    const std::vector<PlannedTrial>& plan, const std::string& form) {
  Stmt insert =
      Prepare(file, db,
              "INSERT INTO studies (name, file, definition, operators, design, "
              "trial_cap_s, created_utc, definition_form) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
              "cannot insert the study");
  Binder(file, db, insert.get())
      .Text(config.name)
      .Text(std::filesystem::absolute(config.file).string())
      .Text(FileText(config.file))
      .Text(config.operators)
      .Text(ToString(config.order))
      .Real(config.trial_cap_s)
      .Text(NowUtc())
      .Text(form);
  StepDone(file, db, insert.get(), "cannot insert the study");
  const int64_t id = sqlite3_last_insert_rowid(db);
  Stmt condition = Prepare(
      file, db,
      "INSERT INTO study_conditions (study_id, position, name, interface) VALUES (?, ?, ?, ?)",
      "cannot insert a condition");
  for (size_t i = 0; i < config.conditions.size(); ++i) {
    sqlite3_reset(condition.get());
    Binder(file, db, condition.get())
        .Int(id)
        .Int(static_cast<int64_t>(i))
        .Text(config.conditions[i].name)
        .Text(config.conditions[i].interface);
    StepDone(file, db, condition.get(), "cannot insert condition " + config.conditions[i].name);
  }
  Stmt participant = Prepare(file, db,
                             "INSERT INTO study_participants (study_id, participant, row_index, "
                             "profile, added_utc) VALUES (?, ?, ?, ?, ?)",
                             "cannot insert a participant");
  for (size_t i = 0; i < config.participants.size(); ++i) {
    sqlite3_reset(participant.get());
    Binder(file, db, participant.get())
        .Int(id)
        .Text(config.participants[i].id)
        .Int(static_cast<int64_t>(i))
        .Text(config.participants[i].profile)
        .Text(NowUtc());
    StepDone(file, db, participant.get(), "cannot insert participant " + config.participants[i].id);
  }
  InsertPlan(file, db, id, plan);
  return id;
}

constexpr const char* kChangedStudy =
    "; a changed study is a new one: give it another name (or put the file back as it was)";

/// Resuming: the study on record is the study. Everything that defines it
/// first, each changed key named with both values.
void CheckDefinitionUnchanged(const std::filesystem::path& file, const StudyConfig& config,
                              const std::string& recorded_form,
                              const std::vector<DefiningValue>& definition) {
  const std::vector<std::string> changes =
      DefinitionChanges(ParseDefinition(recorded_form), definition);
  if (changes.empty()) return;
  constexpr size_t kNamed =
      8;  // a track file rewritten changes every point: the first few say enough
  std::string named;
  bool participants = false;
  for (size_t i = 0; i < changes.size(); ++i) {
    participants = participants || changes[i].rfind("participants: ", 0) == 0;
    if (i < kNamed) named += (i == 0 ? "" : "; ") + changes[i];
  }
  if (changes.size() > kNamed)
    named += "; and " + std::to_string(changes.size() - kNamed) + " more";
  // The file's participants are its rows of the design; more people join
  // an open person study in the console, after them.
  const std::string hint = participants && config.operators == "person"
                               ? " (participants who join later are added in the console)"
                               : "";
  throw std::runtime_error("study '" + config.name + "' in " + file.string() +
                           " was planned with " + named + hint + kChangedStudy);
}

/// Then the plan (for a study planned before its definition was kept, the
/// only check there is). Participants added in the console come after the
/// file's: the file's plan is the record's beginning.
void CheckPlanUnchanged(const std::filesystem::path& file, const StudyConfig& config,
                        const std::vector<PlannedTrial>& recorded,
                        const std::vector<PlannedTrial>& plan) {
  std::string difference;
  if (recorded.size() < plan.size()) {
    difference = std::to_string(recorded.size()) + " trials on record, " +
                 std::to_string(plan.size()) + " in the file";
  } else {
    for (size_t i = 0; i < plan.size() && difference.empty(); ++i) {
      const PlannedTrial& a = recorded[i];
      const PlannedTrial& b = plan[i];
      if (a.participant != b.participant || a.position != b.position ||
          a.condition != b.condition) {
        difference = "trial " + std::to_string(i + 1) + " is " + Describe(a) + " on record, " +
                     Describe(b) + " in the file";
      }
    }
  }
  if (!difference.empty()) {
    throw std::runtime_error("study '" + config.name + "' in " + file.string() +
                             " was planned differently (" + difference + ")" + kChangedStudy);
  }
}

}  // namespace

StudyStore::StudyStore(record::Recorder& recorder, const StudyConfig& config,
                       const std::vector<PlannedTrial>& plan)
    : recorder_(recorder) {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  // Before any write: a track that cannot be loaded stops the study here.
  const std::vector<DefiningValue> definition = StudyDefinition(config);
  const std::string form = DefinitionText(definition);
  std::string recorded_form;
  Transaction txn(file, db, "BEGIN IMMEDIATE");
  {
    Stmt find = Prepare(file, db, "SELECT id, definition_form FROM studies WHERE name = ?",
                        "cannot look up the study");
    Binder(file, db, find.get()).Text(config.name);
    if (sqlite3_step(find.get()) == SQLITE_ROW) {
      Reader r(find.get());
      id_ = r.Int();
      recorded_form = r.Text();
      resumed_ = true;
    }
  }
  if (!resumed_) {
    id_ = InsertStudy(file, db, config, plan, form);
    txn.Commit();
    Event("planned", "", 0, std::to_string(plan.size()) + " trials, " + ToString(config.order));
    return;
  }
  txn.Commit();
  if (!recorded_form.empty()) CheckDefinitionUnchanged(file, config, recorded_form, definition);
  CheckPlanUnchanged(file, config, Plan(), plan);
  if (recorded_form.empty()) {
    // A study planned before the database kept definitions (schema v5 and
    // earlier): its plan matches, which is all that can be checked; from now
    // on it is held to the file as it is at this resume.
    Transaction keep(file, db, "BEGIN IMMEDIATE");
    {
      Stmt update = Prepare(file, db, "UPDATE studies SET definition_form = ? WHERE id = ?",
                            "cannot keep the study's definition");
      Binder(file, db, update.get()).Text(form).Int(id_);
      StepDone(file, db, update.get(), "cannot keep the study's definition");
    }
    Event("definition kept", "", 0,
          "planned before its definition was kept; the file's as of this resume");
    keep.Commit();
  }
}

std::vector<std::string> StudyStore::Participants() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select = Prepare(
      file, db, "SELECT participant FROM study_participants WHERE study_id = ? ORDER BY row_index",
      "cannot read the participants");
  Binder(file, db, select.get()).Int(id_);
  std::vector<std::string> ids;
  while (sqlite3_step(select.get()) == SQLITE_ROW) ids.push_back(Reader(select.get()).Text());
  return ids;
}

void StudyStore::AddParticipant(const std::string& participant,
                                const std::vector<PlannedTrial>& trials) {
  recorder_.RequireInPlace("add participant " + participant);
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Transaction txn(file, db, "BEGIN IMMEDIATE");
  const std::vector<std::string> ids = Participants();
  if (std::find(ids.begin(), ids.end(), participant) != ids.end()) {
    throw AlreadyAnswered("participant " + participant + " is in the study already");
  }
  {
    Stmt insert = Prepare(
        file, db,
        "INSERT INTO study_participants (study_id, participant, row_index, profile, added_utc) "
        "VALUES (?, ?, ?, '', ?)",
        "cannot insert a participant");
    Binder(file, db, insert.get())
        .Int(id_)
        .Text(participant)
        .Int(static_cast<int64_t>(ids.size()))
        .Text(NowUtc());
    StepDone(file, db, insert.get(), "cannot insert participant " + participant);
    std::vector<PlannedTrial> planned = trials;
    for (PlannedTrial& t : planned) t.participant = participant;
    InsertPlan(file, db, id_, planned);
    Event("participant added", participant, 0, std::to_string(trials.size()) + " trials planned");
  }
  txn.Commit();
}

std::vector<PlannedTrial> StudyStore::Plan() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  // Participants in the order they were added, each by position.
  Stmt select = Prepare(
      file, db,
      "SELECT p.participant, p.position, p.condition, p.repetition, p.device FROM study_plan p "
      "JOIN study_participants s ON s.study_id = p.study_id AND s.participant = p.participant "
      "WHERE p.study_id = ? ORDER BY s.row_index, p.position",
      "cannot read the plan");
  Binder(file, db, select.get()).Int(id_);
  std::vector<PlannedTrial> plan;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Reader r(select.get());
    PlannedTrial t;
    t.participant = r.Text();
    t.position = static_cast<int>(r.Int());
    t.condition = r.Text();
    t.repetition = static_cast<int>(r.Int());
    t.device = r.Text();
    plan.push_back(t);
  }
  return plan;
}

namespace {

/// A trial's row in the column order both Trials() and Superseded() select:
/// participant, position, condition, run_id, lap_time_s, completed,
/// obstacles, outcome, attempt, approach_s, flags, device.
void ReadTrialRow(Reader& r, TrialRow& t) {
  t.participant = r.Text();
  t.position = static_cast<int>(r.Int());
  t.condition = r.Text();
  t.run_id = r.Int();
  t.lap_time_s = r.Real();
  t.completed = r.Bool();
  t.obstacles = static_cast<int>(r.Int());
  t.outcome = r.Text();
  t.attempt = static_cast<int>(r.Int());
  t.approach_s = r.Real();
  t.flags = r.Text();
  t.device = r.Text();
}

}  // namespace

std::vector<TrialRow> StudyStore::Trials() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select = Prepare(
      file, db,
      "SELECT t.participant, t.position, t.condition, t.run_id, t.lap_time_s, t.completed, "
      "t.obstacles, t.outcome, t.attempt, t.approach_s, t.flags, t.device FROM study_trials t "
      "JOIN "
      "study_participants s ON "
      "s.study_id = t.study_id AND s.participant = t.participant WHERE t.study_id = ? "
      "ORDER BY s.row_index, t.position",
      "cannot read the trials");
  Binder(file, db, select.get()).Int(id_);
  std::vector<TrialRow> rows;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Reader r(select.get());
    TrialRow t;
    ReadTrialRow(r, t);
    rows.push_back(t);
  }
  return rows;
}

std::optional<PlannedTrial> StudyStore::NextTrial() const {
  const std::vector<TrialRow> done = Trials();
  for (const PlannedTrial& t : Plan()) {
    bool found = false;
    for (const TrialRow& row : done)
      found = found || (row.participant == t.participant && row.position == t.position);
    if (!found) return t;
  }
  return std::nullopt;
}

int StudyStore::TrialsDone(const std::string& participant) const {
  int count = 0;
  for (const TrialRow& row : Trials()) count += row.participant == participant ? 1 : 0;
  return count;
}

std::string TrialFlags(const record::RunRecord& run) {
  std::string flags;
  const auto add = [&flags](const std::string& what) {
    flags += (flags.empty() ? "" : "; ") + what;
  };
  if (run.servo_rate_short) add("servo rate short");
  if (run.physics_rate_short) add("physics rate short");
  // The counters that say the operator's loop, the link or the vehicle
  // misbehaved (README's list); the others (forces clamped...) are the
  // safety doing its job.
  static const std::pair<const char*, const char*> kSpoilers[] = {
      {"link_states_missed", "link states missed"},
      {"vehicle_commands_dropped", "vehicle commands dropped"},
      {"vehicle_watchdog_trips", "vehicle watchdog trips"},
      {"servo_device_lost_ticks", "device lost ticks"},
      {"video_decode_failures", "video decode failures"},
  };
  for (const auto& [name, text] : kSpoilers) {
    for (const record::RunCounter& c : run.counters) {
      if (c.name == name && c.value > 0) add(std::string(text) + " " + std::to_string(c.value));
    }
  }
  return flags;
}

bool FinishesTrial(const std::string& outcome) {
  using mediator::Outcome;
  return outcome == ToString(Outcome::kCompleted) || outcome == ToString(Outcome::kLapCap) ||
         outcome == ToString(Outcome::kTimeLimit) || outcome == ToString(Outcome::kCrashed);
}

record::Recorder::AlsoSave StudyStore::TrialWriter(const PlannedTrial& trial, double cap_s) const {
  const int64_t study = id_;
  const std::filesystem::path file = recorder_.path();
  return [study, file, trial, cap_s](sqlite3* db, int64_t run_id, const record::RunRecord& run) {
    if (!FinishesTrial(run.outcome)) return;
    const bool completed = run.completed && std::isfinite(run.lap_time_s);
    // The thesis's rule: an unfinished lap counts as the cap.
    const double scored = completed ? std::min(run.lap_time_s, cap_s) : cap_s;
    Stmt insert = Prepare(
        file, db,
        "INSERT INTO study_trials (study_id, participant, position, condition, run_id, "
        "lap_time_s, completed, obstacles, outcome, attempt, finished_utc, approach_s, flags, "
        "device) VALUES "
        "(?, ?, ?, ?, ?, ?, ?, ?, ?, 1 + (SELECT COUNT(*) FROM study_events WHERE study_id = ? "
        "AND kind = 'redo' AND participant = ? AND position = ?), ?, ?, ?, ?)",
        "cannot prepare the trial row");
    Binder(file, db, insert.get())
        .Int(study)
        .Text(trial.participant)
        .Int(trial.position)
        .Text(trial.condition)
        .Int(run_id)
        .Real(scored)
        .Int(completed ? 1 : 0)
        .Int(run.obstacles_touched)
        .Text(run.outcome)
        .Int(study)
        .Text(trial.participant)
        .Int(trial.position)
        .Text(NowUtc())
        .RealOrNull(run.approach_s, std::isfinite(run.approach_s))
        .Text(TrialFlags(run))
        .Text(trial.device);
    StepDone(file, db, insert.get(),
             "cannot record trial " + Describe(trial) + " (already recorded?)");
  };
}

bool StudyStore::Redo(const std::string& participant, int position, const std::string& why) {
  recorder_.RequireInPlace("take back the trial of participant " + participant);
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Transaction txn(file, db, "BEGIN IMMEDIATE");
  {
    // Kept as it was: the report lists what was run again, and why.
    Stmt keep = Prepare(
        file, db,
        "INSERT INTO study_superseded_trials (study_id, participant, position, condition, run_id, "
        "lap_time_s, completed, obstacles, outcome, attempt, finished_utc, approach_s, flags, "
        "device, superseded_utc, why) SELECT study_id, participant, position, condition, run_id, "
        "lap_time_s, completed, obstacles, outcome, attempt, finished_utc, approach_s, flags, "
        "device, ?, ? FROM "
        "study_trials WHERE study_id = ? AND participant = ? AND position = ?",
        "cannot keep the trial taken back");
    Binder(file, db, keep.get()).Text(NowUtc()).Text(why).Int(id_).Text(participant).Int(position);
    StepDone(file, db, keep.get(), "cannot keep the trial taken back");
  }
  Stmt remove = Prepare(
      file, db, "DELETE FROM study_trials WHERE study_id = ? AND participant = ? AND position = ?",
      "cannot take the trial back");
  Binder(file, db, remove.get()).Int(id_).Text(participant).Int(position);
  StepDone(file, db, remove.get(), "cannot take the trial back");
  if (sqlite3_changes(db) == 0) return false;  // rolled back: nothing to redo
  remove.reset();
  Event("redo", participant, position, why);
  txn.Commit();
  return true;
}

bool StudyStore::RedoFlaggedOnce(const PlannedTrial& trial) {
  for (const TrialRow& row : Trials()) {
    if (row.participant != trial.participant || row.position != trial.position) continue;
    if (row.flags.empty() || row.attempt > 1) return false;
    return Redo(trial.participant, trial.position,
                "flagged (" + row.flags + "): run again once by itself");
  }
  return false;
}

std::vector<SupersededTrial> StudyStore::Superseded() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select = Prepare(
      file, db,
      "SELECT participant, position, condition, run_id, lap_time_s, completed, obstacles, outcome, "
      "attempt, approach_s, flags, device, why, superseded_utc FROM study_superseded_trials "
      "WHERE "
      "study_id = ? ORDER BY id",
      "cannot read the superseded trials");
  Binder(file, db, select.get()).Int(id_);
  std::vector<SupersededTrial> rows;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Reader r(select.get());
    SupersededTrial s;
    ReadTrialRow(r, s.trial);
    s.why = r.Text();
    s.superseded_utc = r.Text();
    rows.push_back(s);
  }
  return rows;
}

bool StudyStore::Answered(const std::string& participant, const std::string& condition,
                          const std::string& questionnaire) const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select =
      Prepare(file, db,
              "SELECT COUNT(*) FROM study_answers WHERE study_id = ? AND participant = ? AND "
              "condition = ? AND questionnaire = ?",
              "cannot read the answers");
  Binder(file, db, select.get()).Int(id_).Text(participant).Text(condition).Text(questionnaire);
  return sqlite3_step(select.get()) == SQLITE_ROW && sqlite3_column_int64(select.get(), 0) > 0;
}

void StudyStore::SaveAnswers(const std::string& participant, const std::string& condition,
                             const std::string& questionnaire,
                             const std::vector<std::pair<std::string, std::string>>& item_values) {
  recorder_.RequireInPlace("record the answers of participant " + participant);
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Transaction txn(file, db, "BEGIN IMMEDIATE");
  if (Answered(participant, condition, questionnaire)) {
    throw AlreadyAnswered("participant " + participant + " has already answered '" + questionnaire +
                          "' for condition " + condition);
  }
  Stmt insert = Prepare(
      file, db,
      "INSERT INTO study_answers (study_id, participant, condition, questionnaire, item, value, "
      "answered_utc) VALUES (?, ?, ?, ?, ?, ?, ?)",
      "cannot prepare the answers");
  const std::string now = NowUtc();
  for (const auto& [item, value] : item_values) {
    sqlite3_reset(insert.get());
    Binder(file, db, insert.get())
        .Int(id_)
        .Text(participant)
        .Text(condition)
        .Text(questionnaire)
        .Text(item)
        .Text(value)
        .Text(now);
    StepDone(file, db, insert.get(), "cannot record the answer to '" + item + "'");
  }
  insert.reset();
  txn.Commit();
}

std::vector<AnswerRow> StudyStore::Answers() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select =
      Prepare(file, db,
              "SELECT participant, condition, questionnaire, item, value FROM study_answers WHERE "
              "study_id = ? ORDER BY rowid",
              "cannot read the answers");
  Binder(file, db, select.get()).Int(id_);
  std::vector<AnswerRow> rows;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Reader r(select.get());
    AnswerRow a;
    a.participant = r.Text();
    a.condition = r.Text();
    a.questionnaire = r.Text();
    a.item = r.Text();
    a.value = r.Text();
    rows.push_back(a);
  }
  return rows;
}

void StudyStore::SaveNote(const std::string& participant, int position, const std::string& text) {
  recorder_.RequireInPlace("record the note on participant " + participant);
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Transaction txn(file, db, "BEGIN IMMEDIATE");
  {
    Stmt insert =
        Prepare(file, db,
                "INSERT INTO study_notes (study_id, participant, position, text, noted_utc) VALUES "
                "(?, ?, ?, ?, ?)",
                "cannot prepare the note");
    Binder(file, db, insert.get())
        .Int(id_)
        .Text(participant)
        .Int(position)
        .Text(text)
        .Text(NowUtc());
    StepDone(file, db, insert.get(), "cannot record the note on participant " + participant);
  }
  txn.Commit();
}

std::vector<NoteRow> StudyStore::Notes() const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select =
      Prepare(file, db,
              "SELECT participant, position, text, noted_utc FROM study_notes WHERE study_id = ? "
              "ORDER BY id",
              "cannot read the notes");
  Binder(file, db, select.get()).Int(id_);
  std::vector<NoteRow> rows;
  while (sqlite3_step(select.get()) == SQLITE_ROW) {
    Reader r(select.get());
    NoteRow n;
    n.participant = r.Text();
    n.position = static_cast<int>(r.Int());
    n.text = r.Text();
    n.noted_utc = r.Text();
    rows.push_back(n);
  }
  return rows;
}

bool StudyStore::Practised(const std::string& participant) const {
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt select = Prepare(file, db,
                        "SELECT COUNT(*) FROM study_events WHERE study_id = ? AND kind = "
                        "'practice' AND participant = ?",
                        "cannot read the events");
  Binder(file, db, select.get()).Int(id_).Text(participant);
  return sqlite3_step(select.get()) == SQLITE_ROW && sqlite3_column_int(select.get(), 0) > 0;
}

void StudyStore::Event(const std::string& kind, const std::string& participant, int position,
                       const std::string& detail) {
  recorder_.RequireInPlace("record the event '" + kind + "'");
  sqlite3* db = recorder_.handle();
  const std::filesystem::path& file = recorder_.path();
  Stmt insert = Prepare(
      file, db,
      "INSERT INTO study_events (study_id, t_utc, kind, participant, position, detail) VALUES "
      "(?, ?, ?, ?, ?, ?)",
      "cannot record a study event");
  Binder(file, db, insert.get())
      .Int(id_)
      .Text(NowUtc())
      .Text(kind)
      .Text(participant)
      .Int(position)
      .Text(detail);
  StepDone(file, db, insert.get(), "cannot record the event '" + kind + "'");
}

}  // namespace haptel::study
