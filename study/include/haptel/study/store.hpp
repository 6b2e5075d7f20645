#pragma once
/// @file A study's tables in the run database (schema v4, v6's
/// definition_form, v10's notes, v14's devices; recorder.cpp): the study, what defines it
/// (definition.hpp) and its plan, written once when it is first run; one trial row per
/// planned trial, written in its run's own transaction; the questionnaire
/// answers, one transaction per questionnaire; the experimenter's notes; and
/// an event log.
///
/// A study killed at any point (kill -9, power cut) finds on the next start
/// exactly the trials and answers that were committed: it resumes at the
/// first planned trial without a row, and nothing is recorded twice (the
/// tables' keys forbid it).
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "haptel/config/study.hpp"
#include "haptel/record/recorder.hpp"

namespace haptel::study {

/// One trial of the plan: a participant drives a condition at a position of
/// their sequence (1-based), with the condition's input device.
struct PlannedTrial {
  std::string participant;
  int position = 0;
  std::string condition;
  int repetition = 1;
  /// The device's name (StudyCondition::device_name: "mouse", "sim"); "":
  /// planned before the database kept it (schema v14).
  std::string device{};
};

/// Whether a run with this outcome (mediator::ToString) finishes a trial:
/// completed, or ended by the lap cap, the time limit or a crash (the
/// pilot's own doing: scored at the cap). Faults — a lost vehicle or
/// device, an interruption — do not.
bool FinishesTrial(const std::string& outcome);

/// A finished trial as recorded.
struct TrialRow {
  std::string participant;
  int position = 0;
  std::string condition;
  int64_t run_id = 0;
  double lap_time_s = 0.0;  ///< as scored, on the lap's clock: the cap for an unfinished lap
  /// Before the lap's clock started (the approach to the start line, a
  /// cockpit's grasp), s; not part of the score. NaN: recorded before v8.
  double approach_s = std::numeric_limits<double>::quiet_NaN();
  bool completed = false;
  int obstacles = 0;
  std::string outcome;
  int attempt = 1;
  /// What could have spoiled the trial, from its run (TrialFlags); "": nothing.
  std::string flags;
  /// The input device it was driven with (PlannedTrial::device); "":
  /// recorded before the database kept it (schema v14).
  std::string device{};
};

/// A trial row taken back to be run again (a redo), kept: the report counts
/// only the latest attempt and lists these.
struct SupersededTrial {
  TrialRow trial;
  std::string why;
  std::string superseded_utc;
};

/// What in a trial's run could have spoiled it, "; "-separated ("" when
/// nothing): a loop short of its rate (servo, physics), the link's faults
/// (states missed, commands dropped), the vehicle's watchdog trips, the
/// device lost, video that could not be decoded. A trial with flags is
/// scored like any other; the report marks it and the experimenter may redo it.
std::string TrialFlags(const record::RunRecord& run);

struct AnswerRow {
  std::string participant;
  std::string condition;
  std::string questionnaire;
  std::string item;
  std::string value;
};

/// One of the experimenter's notes: what they saw during a trial (the
/// thesis's "direct observations"). Position 0: about the participant as a
/// whole (their practice lap, their manner), not one trial.
struct NoteRow {
  std::string participant;
  int position = 0;
  std::string text;
  std::string noted_utc;  ///< when it was written, ISO 8601 UTC
};

/// A questionnaire answered a second time (a form submitted twice), or a
/// participant added twice.
class AlreadyAnswered : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class StudyStore {
 public:
  /// Opens the study `config.name` in `recorder`'s database, creating it with
  /// `plan` and its definition (StudyDefinition) the first time. A study
  /// already there must be defined the same way now — every key of its
  /// definition, and the file's plan the beginning of the record's (the
  /// console's participants come after) — otherwise throws
  /// std::runtime_error naming each changed key with both values: a changed
  /// study is a new one, under a new name. A study planned before the
  /// database kept definitions (schema v5) is checked by its plan alone, and
  /// keeps the file's definition from this resume on. Throws ConfigError when
  /// the track cannot be loaded. Keeps a reference to `recorder`.
  StudyStore(record::Recorder& recorder, const StudyConfig& config,
             const std::vector<PlannedTrial>& plan);

  int64_t id() const { return id_; }
  /// Whether the study was already in the database (this run resumes it).
  bool resumed() const { return resumed_; }

  std::vector<PlannedTrial> Plan() const;
  /// The participants in the order they joined (the file's first).
  std::vector<std::string> Participants() const;
  /// A participant added in the console, with their planned trials
  /// (PlanParticipant), in one transaction with a 'participant added' event.
  /// Throws AlreadyAnswered if the id is taken.
  void AddParticipant(const std::string& participant, const std::vector<PlannedTrial>& trials);
  std::vector<TrialRow> Trials() const;
  /// The first planned trial without a row (participants in plan order,
  /// each by position); nullopt when all are done.
  std::optional<PlannedTrial> NextTrial() const;
  /// How many trials `participant` has finished.
  int TrialsDone(const std::string& participant) const;

  /// For Recorder::Save: writes the trial's row in the run's transaction,
  /// scored from the run on the lap's clock (an unfinished lap at the cap),
  /// with the run's approach_s beside it — only when the
  /// run's outcome finishes a trial (FinishesTrial): a run that ended in a
  /// fault (vehicle or device lost, interrupted) is recorded, the trial is
  /// not, and a resumed study runs it again. Throws if the trial already
  /// has a row (the run is then rolled back too).
  record::Recorder::AlsoSave TrialWriter(const PlannedTrial& trial, double cap_s) const;

  /// Takes a finished trial back, to be run again (the experimenter's Redo):
  /// its row moves to the superseded trials with `why`, its run stays, and a
  /// 'redo' event records it — in one transaction; the next row's `attempt`
  /// counts it. False if the trial has no row.
  bool Redo(const std::string& participant, int position, const std::string& why);
  /// A synthetic study's rule for a flagged trial (TrialFlags): its first
  /// attempt is taken back (Redo, kept as superseded) to be run again once
  /// by itself; a second attempt is kept whatever its flags. True if it was
  /// taken back.
  bool RedoFlaggedOnce(const PlannedTrial& trial);
  /// The trials taken back, oldest first: the row as it was, and why.
  std::vector<SupersededTrial> Superseded() const;

  /// Whether `participant` answered `questionnaire` after `condition`.
  bool Answered(const std::string& participant, const std::string& condition,
                const std::string& questionnaire) const;
  /// All answers of one questionnaire in one transaction; throws
  /// AlreadyAnswered if any answer of it is there already.
  void SaveAnswers(const std::string& participant, const std::string& condition,
                   const std::string& questionnaire,
                   const std::vector<std::pair<std::string, std::string>>& item_values);
  std::vector<AnswerRow> Answers() const;

  /// Appends one of the experimenter's notes (a row of its own; a trial may
  /// have several), in its own transaction. The caller checks what it says
  /// (SubmitNote); this only writes.
  void SaveNote(const std::string& participant, int position, const std::string& text);
  /// The notes in the order they were written.
  std::vector<NoteRow> Notes() const;

  /// Whether `participant` has driven their practice lap (a 'practice'
  /// event; one aborted is a 'practice interrupted' event, and does not count).
  bool Practised(const std::string& participant) const;

  /// Appends to the study's event log (start, resume, trial failed, redo...).
  void Event(const std::string& kind, const std::string& participant = "", int position = 0,
             const std::string& detail = "");

 private:
  record::Recorder& recorder_;
  int64_t id_ = 0;
  bool resumed_ = false;
};

}  // namespace haptel::study
