/// @file SQLite-backed run recorder (see recorder.hpp).
///
/// Durability and atomicity: the database runs in WAL mode with
/// synchronous=FULL. A run with its splits, switches, path and contacts goes in
/// one BEGIN IMMEDIATE ... COMMIT transaction, so a process killed mid-write
/// leaves either the whole run or nothing; the next connection recovers the
/// WAL and sees only committed runs. Values are always bound to prepared
/// statements, never formatted into SQL.
///
/// SQLite stores a NaN as NULL; LoadAll maps a NULL REAL back to NaN, so
/// "not measured" metrics round-trip. The path, contact and switch columns are
/// NOT NULL: a NaN time or position there is an error, and the save rolls back.
#include "haptel/record/recorder.hpp"

#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <iterator>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_map>
#include <vector>

#include "haptel/record/sqlite_util.hpp"

namespace haptel::record {
namespace {

using namespace haptel::sql;

/// Schema version stored in PRAGMA user_version.
constexpr int kSchemaVersion = 16;

/// Schema steps: kMigrations[v - 1] takes a database from version v - 1 to v.
/// A new database runs them all, so the upgrade path of an old file is the
/// same SQL every new file is built with.
///
/// v1: runs and their gate splits.
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE IF NOT EXISTS runs (
  id INTEGER PRIMARY KEY,
  started_utc TEXT NOT NULL,
  started_wall_ns INTEGER NOT NULL,
  config_name TEXT NOT NULL,
  track TEXT NOT NULL,
  interface TEXT NOT NULL,
  vehicle TEXT NOT NULL,
  completed INTEGER NOT NULL,
  outcome TEXT NOT NULL,
  lap_time_s REAL,
  gates_passed INTEGER NOT NULL,
  gates_total INTEGER NOT NULL,
  gates_missed INTEGER NOT NULL,
  obstacles_touched INTEGER NOT NULL,
  vehicle_pid INTEGER NOT NULL,
  servo_rate_hz REAL,
  servo_period_p99_us REAL,
  command_rtt_ms_p50 REAL,
  command_rtt_ms_p99 REAL,
  video_frames INTEGER NOT NULL,
  video_fps REAL,
  video_latency_ms_p50 REAL
);
CREATE TABLE IF NOT EXISTS gate_splits (
  run_id INTEGER NOT NULL REFERENCES runs(id),
  gate INTEGER NOT NULL,
  passed INTEGER NOT NULL,
  split_s REAL,
  PRIMARY KEY (run_id, gate)
);
)sql";

/// v2: who drove with what, the view's figures, the run's picture; and per run
/// its interface switches, path and contacts. Runs from v1 get '' for the new
/// text columns and NULL (loaded as NaN: not measured) for the new metrics.
/// Rows of the new tables keep their insertion order in their rowid.
constexpr const char* kSchemaV2 = R"sql(
ALTER TABLE runs ADD COLUMN operator_kind TEXT NOT NULL DEFAULT '';
ALTER TABLE runs ADD COLUMN device TEXT NOT NULL DEFAULT '';
ALTER TABLE runs ADD COLUMN distance_m REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN view_fps REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN view_frame_p99_ms REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN video_to_screen_ms_p50 REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN video_to_screen_ms_p99 REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN picture TEXT NOT NULL DEFAULT '';
CREATE TABLE interface_switches (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  from_interface TEXT NOT NULL,
  to_interface TEXT NOT NULL
);
CREATE INDEX interface_switches_run_id ON interface_switches(run_id);
CREATE TABLE run_path (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  x REAL NOT NULL,
  y REAL NOT NULL,
  speed_mps REAL NOT NULL
);
CREATE INDEX run_path_run_id ON run_path(run_id);
CREATE TABLE run_contacts (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  t_s REAL NOT NULL,
  x REAL NOT NULL,
  y REAL NOT NULL
);
CREATE INDEX run_contacts_run_id ON run_contacts(run_id);
)sql";

/// v3: every loop counter of a run (run_counters: one row per counter, in the
/// session's order), and whether the servo and physics loops kept their rates.
/// Runs from v2 get NULL for the new columns (loaded as NaN and false) and no
/// counters.
constexpr const char* kSchemaV3 = R"sql(
ALTER TABLE runs ADD COLUMN servo_target_hz REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN servo_rate_short INTEGER DEFAULT NULL;
ALTER TABLE runs ADD COLUMN physics_rate_hz REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN physics_target_hz REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN physics_rate_short INTEGER DEFAULT NULL;
CREATE TABLE run_counters (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  name TEXT NOT NULL,
  value INTEGER NOT NULL,
  PRIMARY KEY (run_id, name)
);
)sql";

/// v4: A/B studies (study/store.hpp). A study's plan is fixed when it is
/// first run; each trial row links to its run and is written in the run's own
/// transaction; each questionnaire's answers go in one transaction. The
/// UNIQUE keys make a trial or an answer impossible to record twice.
constexpr const char* kSchemaV4 = R"sql(
CREATE TABLE studies (
  id INTEGER PRIMARY KEY,
  name TEXT NOT NULL UNIQUE,
  file TEXT NOT NULL,
  definition TEXT NOT NULL,
  operators TEXT NOT NULL,
  design TEXT NOT NULL,
  trial_cap_s REAL NOT NULL,
  created_utc TEXT NOT NULL
);
CREATE TABLE study_conditions (
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  position INTEGER NOT NULL,
  name TEXT NOT NULL,
  interface TEXT NOT NULL,
  PRIMARY KEY (study_id, position),
  UNIQUE (study_id, name)
);
CREATE TABLE study_participants (
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  row_index INTEGER NOT NULL,
  profile TEXT NOT NULL,
  added_utc TEXT NOT NULL,
  PRIMARY KEY (study_id, participant),
  UNIQUE (study_id, row_index)
);
CREATE TABLE study_plan (
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  position INTEGER NOT NULL,
  condition TEXT NOT NULL,
  repetition INTEGER NOT NULL,
  PRIMARY KEY (study_id, participant, position)
);
CREATE TABLE study_trials (
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  position INTEGER NOT NULL,
  condition TEXT NOT NULL,
  run_id INTEGER NOT NULL REFERENCES runs(id),
  lap_time_s REAL NOT NULL,
  completed INTEGER NOT NULL,
  obstacles INTEGER NOT NULL,
  outcome TEXT NOT NULL,
  attempt INTEGER NOT NULL,
  finished_utc TEXT NOT NULL,
  PRIMARY KEY (study_id, participant, position)
);
CREATE TABLE study_answers (
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  condition TEXT NOT NULL,
  questionnaire TEXT NOT NULL,
  item TEXT NOT NULL,
  value TEXT NOT NULL,
  answered_utc TEXT NOT NULL,
  PRIMARY KEY (study_id, participant, condition, questionnaire, item)
);
CREATE TABLE study_events (
  id INTEGER PRIMARY KEY,
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  t_utc TEXT NOT NULL,
  kind TEXT NOT NULL,
  participant TEXT NOT NULL DEFAULT '',
  position INTEGER NOT NULL DEFAULT 0,
  detail TEXT NOT NULL DEFAULT ''
);
)sql";

// v5: which kind of vehicle a run drove (sim-robot, can-robot, can-robot-sim).
constexpr const char* kSchemaV5 = R"sql(
ALTER TABLE runs ADD COLUMN vehicle_kind TEXT NOT NULL DEFAULT '';
)sql";

// v6: what defines each study, in canonical form (study/definition.hpp), so
// that a study resumed from a changed file is refused naming what changed.
// A study planned before v6 gets '' (it had none); the store keeps its form
// on the first resume.
constexpr const char* kSchemaV6 = R"sql(
ALTER TABLE studies ADD COLUMN definition_form TEXT NOT NULL DEFAULT '';
)sql";

// v7: the predictive display: whether the operator saw the prediction, and
// the model's error against each state (NULL: no state to compare); the
// link's injected fault ('' none), which a study's trials share.
constexpr const char* kSchemaV7 = R"sql(
ALTER TABLE runs ADD COLUMN predict INTEGER NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN link_fault TEXT NOT NULL DEFAULT '';
ALTER TABLE runs ADD COLUMN prediction_error_m_p50 REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN prediction_error_m_p95 REAL DEFAULT NULL;
)sql";

// v8: one clock for a study's cap: the lap's, from the start line; the time
// before the line (the approach, a cockpit's grasp) recorded apart, on the
// run and on its trial's row (NULL: recorded before v8). And what could have
// spoiled each trial (study/store.hpp TrialFlags; '': nothing seen).
constexpr const char* kSchemaV8 = R"sql(
ALTER TABLE runs ADD COLUMN approach_s REAL DEFAULT NULL;
ALTER TABLE study_trials ADD COLUMN approach_s REAL DEFAULT NULL;
ALTER TABLE study_trials ADD COLUMN flags TEXT NOT NULL DEFAULT '';
)sql";

// v9: the video as received: its bitrate (kbit/s) and the time the screen
// showed an old picture marked stale while a key frame was awaited.
constexpr const char* kSchemaV9 = R"sql(
ALTER TABLE runs ADD COLUMN video_kbps REAL NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN video_stale_s REAL NOT NULL DEFAULT 0;
)sql";

// v10: the experimenter's notes (study/store.hpp SaveNote): what they saw
// during a trial, the thesis's "direct observations", one row per note, kept
// in the order written (position 0: about the participant, not one trial).
// And the trials taken back to be run again (a redo; a synthetic study's
// flagged trial run again once): the row as it was, moved here with why,
// so the report counts only the latest attempt and lists the others.
constexpr const char* kSchemaV10 = R"sql(
CREATE TABLE study_notes (
  id INTEGER PRIMARY KEY,
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  position INTEGER NOT NULL,
  text TEXT NOT NULL,
  noted_utc TEXT NOT NULL
);
CREATE INDEX study_notes_study_id ON study_notes(study_id);
CREATE TABLE study_superseded_trials (
  id INTEGER PRIMARY KEY,
  study_id INTEGER NOT NULL REFERENCES studies(id) ON DELETE CASCADE,
  participant TEXT NOT NULL,
  position INTEGER NOT NULL,
  condition TEXT NOT NULL,
  run_id INTEGER NOT NULL REFERENCES runs(id),
  lap_time_s REAL NOT NULL,
  completed INTEGER NOT NULL,
  obstacles INTEGER NOT NULL,
  outcome TEXT NOT NULL,
  attempt INTEGER NOT NULL,
  finished_utc TEXT NOT NULL,
  approach_s REAL,
  flags TEXT NOT NULL,
  superseded_utc TEXT NOT NULL,
  why TEXT NOT NULL
);
CREATE INDEX study_superseded_trials_study_id ON study_superseded_trials(study_id);
)sql";

// v11: a run in simulated time (`haptel run --simulated-time`): its
// speed-up, simulated seconds per wall-clock second (NULL: a real-time run).
constexpr const char* kSchemaV11 = R"sql(
ALTER TABLE runs ADD COLUMN speedup REAL DEFAULT NULL;
)sql";

// v12: the servo controller's error bits over a run (a blimp's Maestro;
// NULL: a vehicle without one). They were in the JSON line only.
constexpr const char* kSchemaV12 = R"sql(
ALTER TABLE runs ADD COLUMN controller_errors INTEGER DEFAULT NULL;
)sql";

// v13: a hand that lets go stops the vehicle (issue 36): the time the
// operator did not engage the interface, and what the device measured of
// its use: the pseudo-haptic gain (NULL: the device does not bend the
// hand) and the force-feedback effects it played. `device` holds the
// device's driver from now on (the shipped files' names were their drivers').
constexpr const char* kSchemaV13 = R"sql(
ALTER TABLE runs ADD COLUMN disengaged_s REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN pseudo_haptic_gain_mean REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN ff_effects_played INTEGER DEFAULT NULL;
)sql";

// v14: the input device of each study trial (a study names one per
// condition: the mouse, a force-feedback wheel...), by its device file's
// name: the one planned, and the one a recorded (or superseded) trial was
// driven with. Trials planned before v14 get '' (not kept).
constexpr const char* kSchemaV14 = R"sql(
ALTER TABLE study_plan ADD COLUMN device TEXT NOT NULL DEFAULT '';
ALTER TABLE study_trials ADD COLUMN device TEXT NOT NULL DEFAULT '';
ALTER TABLE study_superseded_trials ADD COLUMN device TEXT NOT NULL DEFAULT '';
)sql";

// v15: the run's session file (haptel run --session, a study's trials;
// record/session_recorder.hpp), as its path was given; '' without one.
constexpr const char* kSchemaV15 = R"sql(
ALTER TABLE runs ADD COLUMN session_file TEXT NOT NULL DEFAULT '';
)sql";

// v16: the lap judged from a simulated vehicle's truth record (issue 39;
// JSON only before): whether it was completed, its time and whether that
// time's finish was projected rather than crossed, its gates. NULL: not
// judged (no truth record: a real vehicle, the blimp's course, or before v16).
constexpr const char* kSchemaV16 = R"sql(
ALTER TABLE runs ADD COLUMN completed_truth INTEGER DEFAULT NULL;
ALTER TABLE runs ADD COLUMN lap_time_truth_s REAL DEFAULT NULL;
ALTER TABLE runs ADD COLUMN lap_time_truth_projected INTEGER DEFAULT NULL;
ALTER TABLE runs ADD COLUMN gates_truth_passed INTEGER DEFAULT NULL;
ALTER TABLE runs ADD COLUMN gates_truth_missed INTEGER DEFAULT NULL;
)sql";

constexpr const char* kMigrations[] = {
    kSchemaV1, kSchemaV2,  kSchemaV3,  kSchemaV4,  kSchemaV5,  kSchemaV6,  kSchemaV7,  kSchemaV8,
    kSchemaV9, kSchemaV10, kSchemaV11, kSchemaV12, kSchemaV13, kSchemaV14, kSchemaV15, kSchemaV16};
static_assert(std::size(kMigrations) == kSchemaVersion, "one migration per schema version");

constexpr const char* kInsertRun = R"sql(
INSERT INTO runs (started_utc, started_wall_ns, config_name, track, interface, vehicle,
                  completed, outcome, lap_time_s, gates_passed, gates_total, gates_missed,
                  obstacles_touched, vehicle_pid, servo_rate_hz, servo_period_p99_us,
                  command_rtt_ms_p50, command_rtt_ms_p99, video_frames, video_fps,
                  video_latency_ms_p50, operator_kind, device, distance_m, view_fps,
                  view_frame_p99_ms, video_to_screen_ms_p50, video_to_screen_ms_p99, picture,
                  servo_target_hz, servo_rate_short, physics_rate_hz, physics_target_hz,
                  physics_rate_short, vehicle_kind, predict, link_fault, prediction_error_m_p50,
                  prediction_error_m_p95, approach_s, video_kbps, video_stale_s, speedup,
                  controller_errors, disengaged_s, pseudo_haptic_gain_mean, ff_effects_played,
                  session_file, completed_truth, lap_time_truth_s, lap_time_truth_projected,
                  gates_truth_passed, gates_truth_missed)
VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?,
        ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)
)sql";

constexpr const char* kInsertSplit =
    "INSERT INTO gate_splits (run_id, gate, passed, split_s) VALUES (?, ?, ?, ?)";
constexpr const char* kInsertSwitch =
    "INSERT INTO interface_switches (run_id, t_s, from_interface, to_interface) "
    "VALUES (?, ?, ?, ?)";
constexpr const char* kInsertPathPoint =
    "INSERT INTO run_path (run_id, t_s, x, y, speed_mps) VALUES (?, ?, ?, ?, ?)";
constexpr const char* kInsertContact =
    "INSERT INTO run_contacts (run_id, t_s, x, y) VALUES (?, ?, ?, ?)";
constexpr const char* kInsertCounter =
    "INSERT INTO run_counters (run_id, name, value) VALUES (?, ?, ?)";
constexpr const char* kUpdatePicture = "UPDATE runs SET picture = ? WHERE id = ?";

constexpr const char* kSelectRuns = R"sql(
SELECT id, started_wall_ns, config_name, track, interface, vehicle, completed, outcome,
       lap_time_s, gates_passed, gates_total, gates_missed, obstacles_touched, vehicle_pid,
       servo_rate_hz, servo_period_p99_us, command_rtt_ms_p50, command_rtt_ms_p99,
       video_frames, video_fps, video_latency_ms_p50, operator_kind, device, distance_m,
       view_fps, view_frame_p99_ms, video_to_screen_ms_p50, video_to_screen_ms_p99, picture,
       servo_target_hz, servo_rate_short, physics_rate_hz, physics_target_hz, physics_rate_short,
       vehicle_kind, predict, link_fault, prediction_error_m_p50, prediction_error_m_p95, approach_s,
       video_kbps, video_stale_s, speedup, controller_errors, disengaged_s,
       pseudo_haptic_gain_mean, ff_effects_played, session_file, completed_truth,
       lap_time_truth_s, lap_time_truth_projected, gates_truth_passed, gates_truth_missed
FROM runs ORDER BY id
)sql";

constexpr const char* kSelectSplits =
    "SELECT run_id, gate, passed, split_s FROM gate_splits ORDER BY run_id, gate";
constexpr const char* kSelectSwitches =
    "SELECT run_id, t_s, from_interface, to_interface FROM interface_switches "
    "ORDER BY run_id, rowid";
constexpr const char* kSelectPath =
    "SELECT run_id, t_s, x, y, speed_mps FROM run_path ORDER BY run_id, rowid";
constexpr const char* kSelectContacts =
    "SELECT run_id, t_s, x, y FROM run_contacts ORDER BY run_id, rowid";
constexpr const char* kSelectCounters =
    "SELECT run_id, name, value FROM run_counters ORDER BY run_id, rowid";

/// What to do with a damaged database file.
constexpr const char* kDamagedAdvice =
    ": no run is recorded in it (restore it from a copy, or record to another --database)";

/// Refuses a file whose pages are damaged before anything runs: SQLite reads
/// only the pages a statement needs, so garbage in the middle of the file
/// would otherwise pass the opening and fail the save at the end of the run.
/// `quick_check` reads every page once (O(N) in pages; docs/results.md has
/// its cost on 10 000 runs) and checks the b-trees' structure, the records'
/// formats and NOT NULL, but not that each index matches its table (what
/// integrity_check adds, at O(N log N)). `quick_check(1)` costs the same on an
/// intact file, which it must read whole anyway; on a damaged one it stops
/// at the first fault, which is all the message names.
/// Reads the database once from start to end, so that the integrity check
/// that follows finds its pages in the page cache. The check visits pages in
/// the b-trees' order, scattered over the file: from a cold cache that is
/// random reads (12 s for a 250 MB file on the machine of docs/results.md),
/// where one sequential pass takes 0.5 s. A file larger than half the free
/// memory would not stay cached: it is left to the check's own reads. Best
/// effort: a failure here leaves the check to find whatever is wrong.
///
/// Read through SQLite's own file handle, never a descriptor of our own:
/// closing any descriptor of the file drops every POSIX lock this process
/// holds on it (SQLite's "How To Corrupt An SQLite Database File", 2.2),
/// among them the shared lock that tells another process closing the file
/// that the WAL is in use. That process then checkpoints and deletes the
/// WAL and shared memory under this one's open connections, whose later
/// commits go into the deleted file: lost, or a malformed database.
void ReadIntoPageCache(sqlite3* db) {
  sqlite3_file* file = nullptr;
  if (sqlite3_file_control(db, "main", SQLITE_FCNTL_FILE_POINTER, &file) != SQLITE_OK ||
      file == nullptr || file->pMethods == nullptr) {
    return;
  }
  sqlite3_int64 size = 0;
  if (file->pMethods->xFileSize(file, &size) != SQLITE_OK || size <= 0) return;
  const long page = ::sysconf(_SC_PAGESIZE);
  const long free_pages = ::sysconf(_SC_AVPHYS_PAGES);
  if (page <= 0 || free_pages <= 0 ||
      static_cast<uintmax_t>(size) > static_cast<uintmax_t>(page) * free_pages / 2) {
    return;
  }
  // In order, 1 MiB at a time: the kernel's read-ahead sees a sequential reader.
  constexpr int kChunk = 1 << 20;
  std::vector<char> buffer(kChunk);
  for (sqlite3_int64 at = 0; at < size; at += kChunk) {
    const int n = static_cast<int>(std::min<sqlite3_int64>(kChunk, size - at));
    if (file->pMethods->xRead(file, buffer.data(), n, at) != SQLITE_OK) return;
  }
}

/// quick_check's report on one line, without its "*** in database main ***"
/// heading: "Page 128: btreeInitPage() returns error code 11".
std::string OneLine(const std::string& report) {
  constexpr std::string_view kHeading = "*** in database main ***";
  std::string line;
  size_t start = 0;
  while (start <= report.size()) {
    size_t end = report.find('\n', start);
    if (end == std::string::npos) end = report.size();
    const std::string part = report.substr(start, end - start);
    if (!part.empty() && part != kHeading) line += (line.empty() ? "" : "; ") + part;
    start = end + 1;
  }
  return line;
}

void CheckIntegrity(const std::filesystem::path& file, sqlite3* db) {
  auto damaged = [&](const std::string& what) {
    FailWith(file, "is damaged (SQLite's quick_check: " + what + ")" + kDamagedAdvice);
  };
  ReadIntoPageCache(db);
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db, "PRAGMA quick_check(1)", -1, &raw, nullptr) != SQLITE_OK) {
    sqlite3_finalize(raw);
    // The schema's own pages unreadable: as damaged as any other.
    if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_CORRUPT) damaged(sqlite3_errmsg(db));
    Fail(file, db, "cannot check the file's integrity");
  }
  Stmt check(raw);
  const int rc = sqlite3_step(check.get());
  if (rc == SQLITE_ROW) {
    const std::string verdict = Reader(check.get()).Text();
    if (verdict != "ok") damaged(OneLine(verdict));
    return;
  }
  if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_CORRUPT) damaged(sqlite3_errmsg(db));
  Fail(file, db, "cannot check the file's integrity");
}

}  // namespace

Recorder::Recorder(const std::filesystem::path& database) : path_(database) {
  std::error_code ec;
  if (std::filesystem::is_directory(path_, ec)) FailWith(path_, "is a folder, not a database file");
  // The nearest existing ancestor must be a folder, or nothing can be created under it.
  for (std::filesystem::path up = path_.parent_path(); !up.empty(); up = up.parent_path()) {
    const auto status = std::filesystem::status(up, ec);
    if (status.type() == std::filesystem::file_type::not_found) {
      if (up == up.parent_path()) break;
      continue;
    }
    if (!ec && status.type() != std::filesystem::file_type::directory) {
      FailWith(path_, "cannot create it: '" + up.string() + "' is a file, not a folder");
    }
    break;
  }
  const std::filesystem::path parent = path_.parent_path();
  if (!parent.empty()) {
    std::filesystem::create_directories(parent, ec);
    if (ec) FailWith(path_, "cannot create folder " + parent.string() + ": " + ec.message());
  }
  // SQLite creates the file, and its journal files, beside it: the folder must
  // be writable (SQLite alone would say "unable to open database file").
  const std::filesystem::path folder = parent.empty() ? std::filesystem::path(".") : parent;
  if (::access(folder.c_str(), W_OK) != 0) {
    FailWith(path_,
             "its folder " + folder.string() + " is not writable (" + std::strerror(errno) + ")");
  }

  sqlite3* raw = nullptr;
  const int rc =
      sqlite3_open_v2(path_.c_str(), &raw, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  DbHandle db(raw);  // closed on every exit below, even if open failed
  if (rc != SQLITE_OK) {
    if (!db) FailWith(path_, "cannot open database: out of memory");
    Fail(path_, db.get(), "cannot open database");
  }
  sqlite3_extended_result_codes(db.get(), 1);
  if (sqlite3_busy_timeout(db.get(), kOpenBusyTimeoutMs) != SQLITE_OK) {
    Fail(path_, db.get(), "cannot set busy timeout");
  }
  if (sqlite3_db_readonly(db.get(), "main") == 1) {
    FailWith(path_, "is read-only: runs cannot be recorded in it");
  }

  // WAL keeps readers off the writer's back; either journal mode gives atomic
  // commits, so a file system without WAL support (the pragma then reports the
  // old mode) is acceptable. FULL sync makes a committed run survive power loss.
  Exec(path_, db.get(), "PRAGMA journal_mode=WAL", "cannot set journal mode");
  Exec(path_, db.get(), "PRAGMA synchronous=FULL", "cannot set synchronous mode");
  Exec(path_, db.get(), "PRAGMA foreign_keys=ON", "cannot enable foreign keys");
  CheckIntegrity(path_, db.get());

  {
    Transaction txn(path_, db.get(), "BEGIN IMMEDIATE");
    Stmt version = Prepare(path_, db.get(), "PRAGMA user_version", "cannot read schema version");
    if (sqlite3_step(version.get()) != SQLITE_ROW) {
      Fail(path_, db.get(), "cannot read schema version");
    }
    const int found = sqlite3_column_int(version.get(), 0);
    version.reset();
    if (found < 0) {
      FailWith(path_, "schema version " + std::to_string(found) + " is not a Haptel schema");
    }
    if (found > kSchemaVersion) {
      FailWith(path_, "schema version " + std::to_string(found) + " is newer than this haptel's (" +
                          std::to_string(kSchemaVersion) +
                          "); record with a newer haptel or another --database");
    }
    if (found == 0) {
      // Every Haptel file has a version >= 1: tables without one are another
      // program's, and a run is not added to them.
      Stmt tables =
          Prepare(path_, db.get(), "SELECT name FROM sqlite_master WHERE type = 'table' LIMIT 1",
                  "cannot read the tables");
      const int rc = sqlite3_step(tables.get());
      if (rc == SQLITE_ROW) {
        FailWith(path_, "not a Haptel database (it has tables, such as '" +
                            Reader(tables.get()).Text() + "', but no Haptel schema version)");
      }
      if (rc != SQLITE_DONE) Fail(path_, db.get(), "cannot read the tables");
    }
    // Every step up to the current version in this one transaction: a
    // migration that fails part-way leaves the file at its old version.
    for (int v = found + 1; v <= kSchemaVersion; ++v) {
      Exec(path_, db.get(), kMigrations[v - 1],
           "cannot " + std::string(found == 0 ? "create" : "migrate") + " schema to version " +
               std::to_string(v));
    }
    if (found < kSchemaVersion) {
      // PRAGMA takes no bound parameters; the value is a compile-time constant.
      const std::string set = "PRAGMA user_version = " + std::to_string(kSchemaVersion);
      Exec(path_, db.get(), set.c_str(), "cannot set schema version");
    }
    txn.Commit();
  }
  if (sqlite3_busy_timeout(db.get(), kSaveBusyTimeoutMs) != SQLITE_OK) {
    Fail(path_, db.get(), "cannot set busy timeout");
  }

  db_ = db.release();
}

Recorder::~Recorder() { sqlite3_close_v2(db_); }

void Recorder::RequireInPlace(const std::string& what) const {
  int moved = 0;
  if (sqlite3_file_control(db_, "main", SQLITE_FCNTL_HAS_MOVED, &moved) == SQLITE_OK &&
      moved != 0) {
    FailWith(path_, "cannot " + what + ": the file was deleted or replaced since it was opened");
  }
}

int64_t Recorder::Save(const RunRecord& run, const AlsoSave& also) {
  RequireInPlace("save the run");
  Transaction txn(path_, db_, "BEGIN IMMEDIATE");

  Stmt insert_run = Prepare(path_, db_, kInsertRun, "cannot prepare run insert");
  Binder(path_, db_, insert_run.get())
      .Text(IsoUtc(run.started_wall_ns))
      .Int(run.started_wall_ns)
      .Text(run.config_name)
      .Text(run.track)
      .Text(run.interface)
      .Text(run.vehicle)
      .Int(run.completed ? 1 : 0)
      .Text(run.outcome)
      .Real(run.lap_time_s)
      .Int(run.gates_passed)
      .Int(run.gates_total)
      .Int(run.gates_missed)
      .Int(run.obstacles_touched)
      .Int(run.vehicle_pid)
      .Real(run.servo_rate_hz)
      .Real(run.servo_period_p99_us)
      .Real(run.command_rtt_ms_p50)
      .Real(run.command_rtt_ms_p99)
      .Int(run.video_frames)
      .Real(run.video_fps)
      .Real(run.video_latency_ms_p50)
      .Text(run.operator_kind)
      .Text(run.device)
      .Real(run.distance_m)
      .Real(run.view_fps)
      .Real(run.view_frame_p99_ms)
      .Real(run.video_to_screen_ms_p50)
      .Real(run.video_to_screen_ms_p99)
      .Text(run.picture)
      .Real(run.servo_target_hz)
      .Int(run.servo_rate_short ? 1 : 0)
      .Real(run.physics_rate_hz)
      .Real(run.physics_target_hz)
      .Int(run.physics_rate_short ? 1 : 0)
      .Text(run.vehicle_kind)
      .Int(run.predict ? 1 : 0)
      .Text(run.link_fault)
      .RealOrNull(run.prediction_error_m_p50, run.prediction_error_m_p50 >= 0.0)
      .RealOrNull(run.prediction_error_m_p95, run.prediction_error_m_p95 >= 0.0)
      .RealOrNull(run.approach_s, std::isfinite(run.approach_s))
      .Real(run.video_kbps)
      .Real(run.video_stale_s)
      .RealOrNull(run.speedup, run.speedup > 0.0)
      .IntOrNull(run.controller_errors, run.controller_errors >= 0)
      .RealOrNull(run.disengaged_s, std::isfinite(run.disengaged_s))
      .RealOrNull(run.pseudo_haptic_gain_mean, std::isfinite(run.pseudo_haptic_gain_mean))
      .IntOrNull(run.ff_effects_played, run.ff_effects_played >= 0)
      .Text(run.session_file)
      .IntOrNull(run.truth_lap.completed ? 1 : 0, run.truth_lap.judged)
      .RealOrNull(run.truth_lap.lap_time_s,
                  run.truth_lap.judged && std::isfinite(run.truth_lap.lap_time_s))
      .IntOrNull(run.truth_lap.projected ? 1 : 0, run.truth_lap.judged)
      .IntOrNull(run.truth_lap.gates_passed, run.truth_lap.judged)
      .IntOrNull(run.truth_lap.gates_missed, run.truth_lap.judged);
  StepDone(path_, db_, insert_run.get(), "cannot insert run");
  const int64_t run_id = sqlite3_last_insert_rowid(db_);

  Stmt insert_split = Prepare(path_, db_, kInsertSplit, "cannot prepare split insert");
  for (const GateSplit& split : run.splits) {
    sqlite3_reset(insert_split.get());
    Binder(path_, db_, insert_split.get())
        .Int(run_id)
        .Int(split.gate)
        .Int(split.passed ? 1 : 0)
        .Real(split.split_s);
    StepDone(path_, db_, insert_split.get(),
             "cannot insert split for gate " + std::to_string(split.gate));
  }

  // One prepared statement per table, reset and rebound per row: a 10-minute
  // lap's 12 000 path points cost one parse, and one sync at the commit.
  Stmt insert_switch = Prepare(path_, db_, kInsertSwitch, "cannot prepare switch insert");
  for (size_t i = 0; i < run.switches.size(); ++i) {
    const SwitchRecord& s = run.switches[i];
    sqlite3_reset(insert_switch.get());
    Binder(path_, db_, insert_switch.get()).Int(run_id).Real(s.t_s).Text(s.from).Text(s.to);
    StepDone(path_, db_, insert_switch.get(),
             "cannot insert interface switch " + std::to_string(i));
  }

  Stmt insert_point = Prepare(path_, db_, kInsertPathPoint, "cannot prepare path insert");
  for (size_t i = 0; i < run.path.size(); ++i) {
    const PathPoint& p = run.path[i];
    sqlite3_reset(insert_point.get());
    Binder(path_, db_, insert_point.get())
        .Int(run_id)
        .Real(p.t_s)
        .Real(p.x)
        .Real(p.y)
        .Real(p.speed_mps);
    StepDone(path_, db_, insert_point.get(), "cannot insert path point " + std::to_string(i));
  }

  Stmt insert_contact = Prepare(path_, db_, kInsertContact, "cannot prepare contact insert");
  for (size_t i = 0; i < run.contacts.size(); ++i) {
    const ContactPoint& c = run.contacts[i];
    sqlite3_reset(insert_contact.get());
    Binder(path_, db_, insert_contact.get()).Int(run_id).Real(c.t_s).Real(c.x).Real(c.y);
    StepDone(path_, db_, insert_contact.get(), "cannot insert contact " + std::to_string(i));
  }

  Stmt insert_counter = Prepare(path_, db_, kInsertCounter, "cannot prepare counter insert");
  for (const RunCounter& c : run.counters) {
    sqlite3_reset(insert_counter.get());
    Binder(path_, db_, insert_counter.get())
        .Int(run_id)
        .Text(c.name)
        .Int(static_cast<int64_t>(c.value));
    StepDone(path_, db_, insert_counter.get(), "cannot insert counter " + c.name);
  }

  // Statements finalized before COMMIT, so none holds the transaction open.
  insert_run.reset();
  insert_split.reset();
  insert_switch.reset();
  insert_point.reset();
  insert_contact.reset();
  insert_counter.reset();
  if (also) also(db_, run_id, run);  // e.g. the study's trial row: in the same transaction
  txn.Commit();
  return run_id;
}

void Recorder::SetPicture(int64_t run_id, const std::filesystem::path& png) {
  Transaction txn(path_, db_, "BEGIN IMMEDIATE");
  Stmt update = Prepare(path_, db_, kUpdatePicture, "cannot prepare picture update");
  Binder(path_, db_, update.get()).Text(png.string()).Int(run_id);
  StepDone(path_, db_, update.get(), "cannot set the picture of run " + std::to_string(run_id));
  if (sqlite3_changes(db_) != 1) {
    FailWith(path_, "cannot set the picture of run " + std::to_string(run_id) + ": no such run");
  }
  update.reset();
  txn.Commit();
}

std::vector<RunRecord> Recorder::LoadAll() const {
  // One read transaction: runs and splits come from the same snapshot even if
  // another process is saving meanwhile.
  Transaction txn(path_, db_, "BEGIN");

  std::vector<RunRecord> runs;
  std::unordered_map<int64_t, size_t> index_of;
  {
    Stmt select = Prepare(path_, db_, kSelectRuns, "cannot prepare run query");
    int rc;
    while ((rc = sqlite3_step(select.get())) == SQLITE_ROW) {
      Reader r(select.get());
      RunRecord run;
      run.id = r.Int();
      run.started_wall_ns = r.Int();
      run.config_name = r.Text();
      run.track = r.Text();
      run.interface = r.Text();
      run.vehicle = r.Text();
      run.completed = r.Bool();
      run.outcome = r.Text();
      run.lap_time_s = r.Real();
      run.gates_passed = static_cast<int>(r.Int());
      run.gates_total = static_cast<int>(r.Int());
      run.gates_missed = static_cast<int>(r.Int());
      run.obstacles_touched = static_cast<int>(r.Int());
      run.vehicle_pid = static_cast<int>(r.Int());
      run.servo_rate_hz = r.Real();
      run.servo_period_p99_us = r.Real();
      run.command_rtt_ms_p50 = r.Real();
      run.command_rtt_ms_p99 = r.Real();
      run.video_frames = r.Int();
      run.video_fps = r.Real();
      run.video_latency_ms_p50 = r.Real();
      run.operator_kind = r.Text();
      run.device = r.Text();
      run.distance_m = r.Real();
      run.view_fps = r.Real();
      run.view_frame_p99_ms = r.Real();
      run.video_to_screen_ms_p50 = r.Real();
      run.video_to_screen_ms_p99 = r.Real();
      run.picture = r.Text();
      run.servo_target_hz = r.Real();
      run.servo_rate_short = r.Bool();
      run.physics_rate_hz = r.Real();
      run.physics_target_hz = r.Real();
      run.physics_rate_short = r.Bool();
      run.vehicle_kind = r.Text();
      run.predict = r.Bool();
      run.link_fault = r.Text();
      const double p50 = r.Real();
      const double p95 = r.Real();
      run.prediction_error_m_p50 = std::isnan(p50) ? -1.0 : p50;
      run.prediction_error_m_p95 = std::isnan(p95) ? -1.0 : p95;
      run.approach_s = r.Real();  // NaN for NULL: recorded before v8
      run.video_kbps = r.Real();
      run.video_stale_s = r.Real();
      const double speedup = r.Real();  // NaN for NULL: a real-time run, or recorded before v11
      run.speedup = std::isnan(speedup) ? -1.0 : speedup;
      run.controller_errors =
          static_cast<int>(r.IntOr(-1));       // NULL: no servo controller, or before v12
      run.disengaged_s = r.Real();             // NaN for NULL: recorded before v13
      run.pseudo_haptic_gain_mean = r.Real();  // NaN for NULL: not measured, or before v13
      run.ff_effects_played = r.IntOr(-1);     // NULL: recorded before v13
      run.session_file = r.Text();             // '' before v15
      // NULL: not judged from a truth record, or recorded before v16.
      const int64_t completed_truth = r.IntOr(-1);
      run.truth_lap.judged = completed_truth >= 0;
      run.truth_lap.completed = completed_truth == 1;
      run.truth_lap.lap_time_s = r.Real();
      run.truth_lap.projected = r.IntOr(0) == 1;
      run.truth_lap.gates_passed = static_cast<int>(r.IntOr(0));
      run.truth_lap.gates_missed = static_cast<int>(r.IntOr(0));
      index_of.emplace(run.id, runs.size());
      runs.push_back(std::move(run));
    }
    if (rc != SQLITE_DONE) Fail(path_, db_, "cannot read runs");
  }
  {
    Stmt select = Prepare(path_, db_, kSelectSplits, "cannot prepare split query");
    int rc;
    while ((rc = sqlite3_step(select.get())) == SQLITE_ROW) {
      Reader r(select.get());
      const int64_t run_id = r.Int();
      GateSplit split;
      split.gate = static_cast<int>(r.Int());
      split.passed = r.Bool();
      split.split_s = r.Real();
      const auto it = index_of.find(run_id);
      if (it != index_of.end()) runs[it->second].splits.push_back(split);
    }
    if (rc != SQLITE_DONE) Fail(path_, db_, "cannot read gate splits");
  }
  // The rows of a run's child table go to that run, in the query's order.
  auto read_children = [&](const char* sql, std::string_view what, auto&& add) {
    Stmt select = Prepare(path_, db_, sql, "cannot prepare " + std::string(what) + " query");
    int rc;
    while ((rc = sqlite3_step(select.get())) == SQLITE_ROW) {
      Reader r(select.get());
      const auto it = index_of.find(r.Int());
      if (it != index_of.end()) add(runs[it->second], r);
    }
    if (rc != SQLITE_DONE) Fail(path_, db_, "cannot read " + std::string(what));
  };
  read_children(kSelectSwitches, "interface switches", [](RunRecord& run, Reader& r) {
    SwitchRecord s;
    s.t_s = r.Real();
    s.from = r.Text();
    s.to = r.Text();
    run.switches.push_back(std::move(s));
  });
  read_children(kSelectPath, "path", [](RunRecord& run, Reader& r) {
    PathPoint p;
    p.t_s = r.Real();
    p.x = r.Real();
    p.y = r.Real();
    p.speed_mps = r.Real();
    run.path.push_back(p);
  });
  read_children(kSelectContacts, "contacts", [](RunRecord& run, Reader& r) {
    ContactPoint c;
    c.t_s = r.Real();
    c.x = r.Real();
    c.y = r.Real();
    run.contacts.push_back(c);
  });
  read_children(kSelectCounters, "counters", [](RunRecord& run, Reader& r) {
    RunCounter c;
    c.name = r.Text();
    c.value = static_cast<uint64_t>(r.Int());
    run.counters.push_back(std::move(c));
  });

  txn.Commit();
  return runs;
}

}  // namespace haptel::record
