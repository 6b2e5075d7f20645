#pragma once
/// @file Records finished runs in a SQLite database.
///
/// One run is written in one transaction (the run row, its gate splits,
/// interface switches, path and contacts), so an interrupted write leaves
/// nothing half-written.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

struct sqlite3;

namespace haptel::record {

/// One gate of a lap: whether it was passed between its posts, and when its
/// line was crossed, in s since the lap started (negative: never reached).
struct GateSplit {
  int gate = 0;
  bool passed = false;
  double split_s = -1.0;
};

/// A switch to another interface during a run (F1–F6), t_s since the session
/// started.
struct SwitchRecord {
  double t_s = 0.0;
  std::string from;
  std::string to;
};

/// Where the vehicle was, world frame (m), and how fast it went; t_s since the
/// session started.
struct PathPoint {
  double t_s = 0.0;
  double x = 0.0;
  double y = 0.0;
  double speed_mps = 0.0;
};

/// Where the vehicle was when a bumper contact began.
struct ContactPoint {
  double t_s = 0.0;
  double x = 0.0;
  double y = 0.0;
};

/// One of the counters the session's parts keep (servo overruns, clamped
/// forces, dropped video frames, ...): names and meanings in docs/results.md, "The
/// JSON line".
struct RunCounter {
  std::string name;
  uint64_t value = 0;
};

/// A parameter the operator side estimated of the vehicle while it drove
/// (mediator/drive_estimator.hpp; the blimp's wind), against the value the
/// simulated vehicle drew (its truth record). JSON only.
struct EstimatedParameter {
  std::string name;  ///< the truth record's name for it ("left_gain", "wind_x")
  double estimate = 0.0;
  double truth = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no truth record
  /// When it first became known, s since the session started (NaN: never;
  /// the estimate is then the vehicle file's value).
  double known_s = std::numeric_limits<double>::quiet_NaN();
};

/// The lap judged again from where a simulated vehicle truly went (its
/// truth record, after the run), by the same rules as the live lap, which a
/// real vehicle's odometry judges: a gate the odometry passed may have been
/// truly missed, and the lap's time differs where the odometry drifted over
/// a line (the blimp's: its landing judged resting on the circle's ground,
/// its contacts the live lap's). In the JSON and the database (v16; its
/// splits in the JSON only); `judged` false without a truth record (a real
/// vehicle).
struct TruthLap {
  bool judged = false;
  bool completed = false;
  /// From the true start-line crossing to the true finish (NaN: not completed).
  double lap_time_s = std::numeric_limits<double>::quiet_NaN();
  /// The finish was projected, not crossed: the run ended as the odometry
  /// crossed the line with the robot truly short of it, and lap_time_s
  /// adds the rest of the way at its true speed (JudgeLapOnTruth). An
  /// estimate, to be reported as one.
  bool projected = false;
  int gates_passed = 0;
  int gates_missed = 0;
  std::vector<GateSplit> splits;
};

/// Everything a run reports, as stored in the database. A metric that was not
/// measured is NaN (stored as NULL); runs recorded before schema v2 load with
/// NaN for v2's metrics, empty strings and empty vectors; before v3, with NaN
/// for v3's rates, false for its flags and no counters.
struct RunRecord {
  int64_t id = 0;               ///< set by Save / Load
  int64_t started_wall_ns = 0;  ///< CLOCK_REALTIME at session start
  std::string config_name;
  std::string track;
  std::string interface;
  std::string vehicle;
  std::string vehicle_kind;  ///< sim-robot, can-robot, can-robot-sim (v5; "" before)
  bool completed = false;
  std::string outcome;      ///< "completed", "lap cap", "vehicle lost", "interrupted", ...
  double lap_time_s = 0.0;  ///< the lap's clock: from the start line
  /// From the session's start to the start line (the approach and, in a
  /// cockpit, the grasp of its controls), s: the whole run when the line
  /// was never reached (v8; NaN before).
  double approach_s = std::numeric_limits<double>::quiet_NaN();
  int gates_passed = 0;
  int gates_total = 0;
  int gates_missed = 0;
  int obstacles_touched = 0;
  int vehicle_pid = 0;
  double servo_rate_hz = 0.0;
  double servo_period_p99_us = 0.0;
  double command_rtt_ms_p50 = 0.0;
  double command_rtt_ms_p99 = 0.0;
  int64_t video_frames = 0;
  double video_fps = 0.0;
  double video_latency_ms_p50 = 0.0;
  double video_kbps = 0.0;  ///< the video's bitrate as received (v9)
  /// Time the screen showed an old picture marked stale, waiting for an
  /// H.264 key frame after a lost or corrupt frame (v8; 0 for JPEG).
  double video_stale_s = 0.0;
  /// The predictive display: whether the operator saw the prediction, and
  /// the error of the pose it showed as the vehicle now against where the
  /// vehicle truly was then (m; from a simulated vehicle's truth record,
  /// after the run; -1: no truth record, or nothing predicted).
  bool predict = false;
  /// The link's injected fault, as LinkFaultText writes it (v7; "": none).
  std::string link_fault;
  /// The truth is taken in the map's frame (TruthInMapFrame in
  /// mediator/prediction_score.hpp): where the vehicle truly was relative to
  /// the as-built track, expressed in the track file's frame by the best
  /// rigid fit of the as-built features onto the file's. A survey's global
  /// turn and offset is a choice of frame, not the predictor's error; a post
  /// standing 2 cm from where the map says still counts.
  double prediction_error_m_p50 = -1.0;
  double prediction_error_m_p95 = -1.0;
  /// The same against the raw truth, in the world frame the vehicle was
  /// placed in (JSON only; equal to the above without map error).
  double prediction_error_world_m_p50 = -1.0;
  double prediction_error_world_m_p95 = -1.0;
  /// The rigid fit taking the as-built track onto its file (JSON only):
  /// its turn (deg), offset (m), the features fitted (wall corners, post
  /// centres; 0: no map error, the identity) and what it leaves (rms, m: the
  /// local map error).
  struct MapFrameFit {
    double rotation_deg = 0.0;
    double offset_x_m = 0.0;
    double offset_y_m = 0.0;
    int features = 0;
    double residual_m_rms = 0.0;
  } map_fit;
  /// A localised robot's map against the track as built, in the map's frame
  /// (JSON only): its wall corners' and post centres' RMS distance (m) from
  /// where they truly stand, as the localiser learnt them (the file's with
  /// the nominal model) and as the file has them; NaN: not scored.
  struct MapEstimate {
    int features = 0;
    double learnt_m_rms = std::numeric_limits<double>::quiet_NaN();
    double file_m_rms = std::numeric_limits<double>::quiet_NaN();
  } map_estimated;
  /// The model the prediction ran: "nominal" or "learn" (JSON only).
  std::string predict_model;
  /// The model's error against each state at the moment it was sampled: its
  /// fit to the vehicle's own odometry (m; -1: no state to compare; JSON only).
  double prediction_error_odometry_m_p50 = -1.0;
  double prediction_error_odometry_m_p95 = -1.0;
  /// Whether the robot's pose was localised on the track (its range scan
  /// against the walls and posts) or its odometry alone (JSON only).
  bool localised = false;
  /// Scans the localiser refused whole, disagreeing with the map wherever
  /// the robot was (track_localiser.hpp; -1: not localised; JSON only).
  int64_t localiser_scans_refused = -1;
  /// The pose each state gave the run (localised, or the odometry) and the
  /// odometry alone, against the truth at that state's moment (m; -1: no
  /// truth record; JSON only): the floor under the prediction's error. In
  /// the map's frame, as prediction_error_m_*.
  double localisation_error_m_p50 = -1.0;
  double localisation_error_m_p95 = -1.0;
  /// The localised pose against the raw truth (world frame; JSON only).
  double localisation_error_world_m_p50 = -1.0;
  double localisation_error_world_m_p95 = -1.0;
  double odometry_error_m_p50 = -1.0;
  double odometry_error_m_p95 = -1.0;
  /// What the predictor estimated of the vehicle, each against its truth.
  std::vector<EstimatedParameter> estimated;
  /// The lap judged from the truth record (v16; NULL before, and when not judged).
  TruthLap truth_lap;
  /// A run in simulated time (`haptel run --simulated-time`): simulated
  /// seconds per wall-clock second over the run (v11; -1: a real-time run).
  double speedup = -1.0;
  /// The error bits the vehicle's servo controller reported over the run,
  /// ORed (a Pololu Maestro's error register: ControllerErrorNames in
  /// mediator/controller_errors.hpp names them; v12; -1: the vehicle has no
  /// servo controller, or the run was recorded before v12).
  int controller_errors = -1;
  std::string operator_kind;  ///< "auto" or "person"
  /// The haptic device's driver: sim, udp, replay, mouse, sdl-ff (v13;
  /// before, the device file's name, the same for the shipped files).
  std::string device;
  /// Time the vehicle was up and the operator did not engage the interface
  /// (a hand let go, out of reach, not yet back at neutral; engagement.hpp
  /// in the mediator), s (v13; NaN before).
  double disengaged_s = 0.0;
  /// How much the device bent the hand's motion from its input's (a mouse's
  /// pseudo-haptics: the hand's displacement over the pointer's, mean; NaN:
  /// the device does not bend it, or recorded before v13).
  double pseudo_haptic_gain_mean = std::numeric_limits<double>::quiet_NaN();
  /// Force-feedback effects the device started (SDL's haptic API; 0 for a
  /// device without; -1: recorded before v13).
  int64_t ff_effects_played = 0;
  /// The run's session file (MCAP: record/session_recorder.hpp), as its
  /// path was given; "" without one, or one that was not saved (v15).
  std::string session_file;
  double distance_m = 0.0;  ///< driven, summed over the vehicle's positions
  double view_fps = 0.0;    ///< the operator's view (0: none)
  double view_frame_p99_ms = 0.0;
  double video_to_screen_ms_p50 = 0.0;  ///< capture stamp -> first shown on screen
  double video_to_screen_ms_p99 = 0.0;
  std::string picture;  ///< the run's PNG (empty: none)
  /// The servo loop's target rate, and whether it fell below 90 % of it over
  /// a progress interval or the run (DESIGN: a loop that cannot keep its rate
  /// says so).
  double servo_target_hz = 0.0;
  bool servo_rate_short = false;
  /// The physics thread's rate and target (0 and 0: no physics world).
  double physics_rate_hz = 0.0;
  double physics_target_hz = 0.0;
  bool physics_rate_short = false;
  /// Every counter, in the session's fixed order (zeros included).
  std::vector<RunCounter> counters;
  std::vector<GateSplit> splits;
  std::vector<SwitchRecord> switches;
  std::vector<PathPoint> path;  ///< one point every 0.05 s
  std::vector<ContactPoint> contacts;
};

class Recorder {
 public:
  /// Opens (creating it and its parent folders if needed) the database and its
  /// schema; an older schema (v1 to v12) is migrated in place, in one
  /// transaction. The schema is read inside a write transaction, so a file
  /// that opens here can be written; every page is checked first (SQLite's
  /// quick_check), so a file damaged inside is refused here, not at the save.
  /// The check reads the whole file (about 2.5 s of CPU per GB, see
  /// docs/results.md); every other failure comes within a second — a file
  /// another connection holds locked is waited for at most kOpenBusyTimeoutMs
  /// — throwing std::runtime_error with a one-line message "database FILE:
  /// what is wrong" (a folder, a path under a regular file, not a database,
  /// damaged, a newer or foreign schema, read-only, locked).
  explicit Recorder(const std::filesystem::path& database);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Writes the run with its splits, switches, path, contacts and counters in
  /// one transaction; returns the run id. On any failure (for instance a NaN
  /// time or coordinate in the path or contacts: those columns are NOT NULL;
  /// or the file was deleted or replaced since it was opened, which SQLite
  /// would otherwise write into the unlinked file) rolls back and throws
  /// std::runtime_error.
  /// What else to write in the run's transaction, given the connection and
  /// the new run's id (throwing rolls the whole run back).
  using AlsoSave = std::function<void(sqlite3* db, int64_t run_id, const RunRecord& run)>;
  int64_t Save(const RunRecord& run, const AlsoSave& also = {});

  /// Sets the picture of a saved run. Throws std::runtime_error if there is
  /// no run `run_id` or the write fails.
  void SetPicture(int64_t run_id, const std::filesystem::path& png);

  /// All runs, oldest first, with their splits (gate order), switches, path
  /// and contacts (in the order saved).
  std::vector<RunRecord> LoadAll() const;

  /// Throws std::runtime_error ("database FILE: cannot WHAT: the file was
  /// deleted or replaced since it was opened") when the file this recorder
  /// opened is no longer at its path: SQLite in WAL mode would go on writing
  /// into the unlinked file, and whatever it wrote would be gone. Every write
  /// to the file (a run, a study's rows) asks first.
  void RequireInPlace(const std::string& what) const;

  const std::filesystem::path& path() const { return path_; }
  /// The open connection, for the tables other parts keep in the same file
  /// (the study store); the schema is this recorder's (PRAGMA user_version).
  sqlite3* handle() const { return db_; }

  /// How long opening waits for a lock another connection holds: long
  /// enough for another haptel's save to finish, short enough that a
  /// program that holds the file tells the user at once (`haptel run` itself
  /// takes ~0.7 s to load its libraries on a busy machine: under 2 s in all).
  static constexpr int kOpenBusyTimeoutMs = 500;
  /// How long a save waits for one: the run's results are worth the wait.
  static constexpr int kSaveBusyTimeoutMs = 10000;

 private:
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
};

}  // namespace haptel::record
