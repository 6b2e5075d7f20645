#pragma once
/// @file One session on the operator side, assembled from parts, each built,
/// started and stopped on its own:
///
/// - the haptic device (HapticSide: sim, udp or replay; HAL; servo loop at 1 kHz),
/// - the vehicle family's part (robot_session.cpp, blimp_session.cpp): its
///   track or course and lap timer, its interfaces (the robot's InterfaceSet:
///   the current one, and those F1–F6 switch to), the physics world when an
///   interface's controls or the scene need one (SessionPhysics: proxy hands,
///   wheel and lever at 1/step_s; built when such an interface is first
///   asked for, not before), and its operator (the automatic driver or
///   pilot, or a person),
/// - the vehicle link (VehicleLink: spawned simulator, DDS, video),
/// - the view and a person's input (SessionView: window or offscreen, MP4),
/// - and the session loop (this thread, `session_rate_hz`; session.cpp, the
///   same for one vehicle and for a fleet), which feeds the operator, runs
///   the interface, sends commands at the interface's command rate, times
///   the lap and watches the vehicle, the device and the person.
///
/// The recorder (Recorder) stores the result afterwards: `haptel run` opens
/// and checks the database before the session starts, and saves into it at
/// the end (or into a fallback file, see unsaved_run.hpp).
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/calibration.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/study.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/mediator/interface_set.hpp"
#include "haptel/mediator/prediction.hpp"
#include "haptel/mediator/run_record.hpp"
#include "haptel/record/session_recorder.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::mediator {

/// What the operator sees: nothing, a window, or an offscreen render (for
/// the MP4 only).
enum class ViewKind { kNone, kWindow, kOffscreen };

/// Whether the session decodes the vehicle's video: only when a view shows or
/// records it (frames are still received and counted without).
constexpr bool DecodesVideo(ViewKind view) { return view != ViewKind::kNone; }

struct SessionSetup {
  RunConfig run;
  TrackConfig track;
  VehicleConfig vehicle;
  /// The run's interfaces in F1–F6 order, and the one it starts with (a
  /// blimp flies with one).
  std::vector<interfaces::InterfaceSpec> interfaces;
  int start_interface = 0;
  /// The physics world, used only when an interface's controls or the
  /// scene have bodies.
  PhysicsConfig physics;
  /// The haptic scene the hands can touch (none: nothing to touch).
  std::optional<Scene> scene;
  DeviceConfig device;
  /// From DeviceCalibrationFor (nullopt: the sim calibrates itself at start).
  std::optional<DeviceCalibration> calibration;
  /// Gravity compensation grid (from device.gravity; empty: none).
  std::optional<GravityGridData> gravity;
  /// haptel-vehicle to spawn; empty: the vehicle runs elsewhere, do not spawn.
  std::filesystem::path vehicle_program;
  /// vehicle.truth_file (the simulated vehicle's truth record, which
  /// `haptel run` asks of it; vehicle.reality the reality it runs) is a
  /// temporary file of this run's: RunAndRecord reads the reality's name
  /// and seed from it, then removes it. Score against it before then.
  bool truth_temporary = false;
  /// Drive a vehicle already running on the domain (`--attach`): nothing is
  /// spawned (vehicle_program is empty) and nothing is stopped at the end
  /// but this run's hold on it.
  bool attach = false;
  bool progress = true;  ///< progress lines on stderr
  /// The predictive display (robot_predictor.hpp, blimp_predictor.hpp):
  /// the operator sees the vehicle where the model says it is now, not
  /// where its delayed state says it was. The model runs either way, for
  /// its error in the record.
  bool predict = false;
  /// The model it runs (prediction.hpp): the vehicle file's, or with what
  /// is learnt of the vehicle while it drives (the default: --predict on is
  /// learn; nominal is for comparing the two).
  PredictionModel predict_model = PredictionModel::kLearn;
  /// Keep everything a robot's predictor consumes (SessionResult::predictor_inputs).
  bool keep_predictor_inputs = false;
  /// Localise a robot whose states carry range scans on the track it drives
  /// (track_localiser.hpp; `--localise on|off`): its pose for the
  /// predictor, the lap's gates, the view and the automatic operator is its
  /// odometry corrected against the track's walls and posts. Without ranges
  /// (the CAN robot) nothing changes either way.
  bool localise = true;
  /// Record the device's readings here for the `replay` driver (empty: none).
  std::filesystem::path trace;
  /// "auto" (the simulated driver; needs the sim device) or "person".
  std::string operator_kind = "auto";
  /// The simulated driver's profile (default: the ideal driver) and the
  /// trials it has driven before (a study's simulated participants).
  DriverProfile driver;
  int driver_experience = 0;
  /// End the run after this long, outcome "time limit" (0: no limit).
  double time_limit_s = 0.0;
  /// End the run when the lap's clock (from the start line) passes this,
  /// outcome "time limit" (0: no limit): a study's trial cap, the same lap
  /// time for every interface whatever its approach and grasp took. Before
  /// the line the approach counts against it, so a run that never reaches
  /// the line ends too.
  double lap_limit_s = 0.0;
  ViewKind view = ViewKind::kNone;
  /// The operator's view as H.264 MP4 (empty: none; needs a view).
  std::filesystem::path record;
  /// The whole run into a session file (record/session_recorder.hpp; its
  /// `file` empty: none): the link's samples, the video, the servo ticks,
  /// the events, the metadata and configuration files.
  record::SessionFileOptions session_file;
  /// The camera's picture fills the view (the thesis's practice lap: the
  /// keyboard and a direct view of the camera) instead of hanging on a
  /// screen before the hands.
  bool direct_view = false;
  /// Only the start interface: no switching (F1–F6), and no other
  /// interface's controls or hands built, so none is drawn over the camera's
  /// picture (a study's practice lap on the keyboard).
  bool single_interface = false;
  /// The third-person view beside the camera's picture (third_person_view.hpp):
  /// a chase camera's picture of the robot on its track, labelled so. A
  /// study's practice lap (the thesis's gave a direct view of the robot),
  /// or haptel run --third-person; only for a simulated robot (the track is
  /// the operator side's), and only with a view. Never in a trial.
  bool third_person = false;
  /// Every part on one simulated clock in this one thread, as fast as the
  /// CPU allows (`haptel run --simulated-time`; simulated_time.hpp): the
  /// servo ticks, the physics steps and the simulated robot's control loop
  /// (stepped in this process, its commands and states delayed by the
  /// link fault's delay), the automatic operator and the session loop. The
  /// same seed gives the same lap to the tick. Only for the automatic
  /// operator and a robot whose kind steps in process, without a view.
  bool simulated_time = false;
  /// The window's title; empty: "Haptel - <run name>".
  std::string title;
  /// Called on the session thread twice a second with what the view's
  /// overlay shows (lap clock, gates, contacts), view or not: a study's
  /// console shows the live trial with it. Must return quickly.
  std::function<void(const view::Overlay&)> on_live;
  /// Called twice a second on the session thread with the vehicle's latest
  /// camera picture as it came (JPEG), when a new one arrived: a study's
  /// console shows it as its thumbnail, through this session's link. Must
  /// return quickly.
  std::function<void(std::vector<uint8_t> jpeg, uint64_t frames)> on_picture;
  /// A blimp's flight (the vehicle is a blimp kind): its course, instead of `track`.
  std::optional<BlimpCourseConfig> course;
};

enum class Outcome {
  kCompleted,
  kLapCap,
  kTimeLimit,
  kVehicleLost,
  kVehicleDidNotStart,
  kDeviceLost,
  kAborted,      ///< the person closed the window or lost their controller
  kInterrupted,  ///< SIGINT / SIGTERM / SIGHUP
  kCrashed,      ///< the blimp hit a building or the ground too fast
  kConflict,     ///< a second vehicle publishes under the same name on the domain
  kRefused,      ///< the vehicle obeys another operator's writer
  /// The vehicle obeyed this run's writer, then another's (or one naming
  /// this run's session): this run's commands are not the ones obeyed.
  kLostControl,
};
std::string ToString(Outcome outcome);
/// The process exit code for an outcome: 0 completed, 3 lost vehicle or
/// device, 2 a link conflict, refusal or control lost (another operator or
/// vehicle on the link: what the run drove was not, or no longer, its
/// own), 1 otherwise.
int ExitCode(Outcome outcome);
/// The exit code, whatever the outcome, of a run the database did not take
/// at the end (its results went to a fallback file; the JSON line says which).
constexpr int kExitNotRecorded = cli::kExitNotRecorded;
/// The exit code of a run recorded in the database whose --record MP4 or
/// whose vehicle's CAN bus log failed (kExitNotRecorded wins over it; it
/// wins over the outcome's code).
constexpr int kExitOutputFailed = cli::kExitOutputFailed;

/// The vehicle's CAN bus log as its last status received reported it (a CAN
/// robot keeping one in can.log_dir; the file is on the vehicle's host).
struct CanLogReport {
  std::string path;          ///< "": the vehicle keeps no log
  uint64_t frames = 0;       ///< frames certainly in the file
  uint64_t frames_lost = 0;  ///< frames not in it because a write failed
  std::string error;         ///< why the log ended ("" while whole)
};

struct SessionResult {
  Outcome outcome = Outcome::kInterrupted;
  std::string message;  ///< one line: why it ended
  RunRecord record;     ///< everything measured, ready for the recorder
  /// What turned the pan/tilt camera's head (view/head_source.hpp: mouse,
  /// gamepad, openxr), and, when it is not what the run asked for, why
  /// ("no OpenXR runtime (...): head follows the mouse"; else empty).
  std::string head_source = "mouse";
  std::string head_fallback;
  uint64_t servo_overruns = 0;
  double lost_detect_s = 0.0;  ///< vehicle or device lost: last sign of life -> detection
  /// The physics thread, when there was one (rate 0 otherwise).
  double physics_rate_hz = 0.0;
  double physics_period_p99_us = 0.0;
  double physics_step_max_us = 0.0;
  uint64_t physics_hand_resets = 0;
  int scene_bodies = 0;  ///< scene objects built into the world
  /// Seconds from the start until the operator's hands held the controls
  /// (0 when there was nothing to grasp; negative if they never did).
  double grasp_s = 0.0;
  /// The session file's fate and counts (its `file` empty: none was asked).
  record::SessionFileReport session_file;
  uint64_t view_record_dropped = 0;  ///< MP4 frames the encoder could not take in time
  /// "" when the --record MP4 was written whole (or none was asked for);
  /// else why not: a failed write ended it (file, OS reason, frames kept).
  std::string view_record_error;
  CanLogReport can_log;
  /// The simulated driver: times a control slipped out of its hand.
  int operator_slips = 0;
  /// What the predictor showed as the vehicle now, one pose a state (the
  /// operator's clock, s from `started_ns`, its MonotonicNs), for scoring
  /// against the simulated vehicle's truth record after the run
  /// (prediction_score.hpp); the 3-D distance counts with `shown_height`
  /// (the blimp).
  std::vector<ShownPose> shown;
  /// A robot's pose at each state's moment as the run took it (localised,
  /// or its odometry) and its odometry alone, on the same clock, scored
  /// like `shown` (RobotPredictor::located, odometry).
  std::vector<ShownPose> located;
  std::vector<ShownPose> odometry;
  /// A localised robot's map at the run's end: each wall corner and post
  /// centre, where the file has it and where the localiser learnt it stands
  /// (the file's, with the nominal model), scored against the as-built
  /// track into RunRecord::estimated (prediction_score.hpp).
  std::vector<std::pair<Vec2, Vec2>> learnt_map;
  int64_t started_ns = 0;
  bool shown_height = false;
  /// With SessionSetup::keep_predictor_inputs, a robot's: everything its
  /// predictor consumed.
  RobotPredictorInputs predictor_inputs;
  /// A simulated-time run: its session's simulated seconds, and the wall
  /// seconds the whole run took (set-up included); 0 in real time.
  double simulated_s = 0.0;
  double wall_s = 0.0;
  /// The CPU time the run's thread used meanwhile (s): on a loaded machine
  /// the speed-up it allows (simulated_s / cpu_s) is what the CPU could do.
  double cpu_s = 0.0;
  /// A simulated-time run's ticks, on its clock: the servo loop's (each
  /// of every arm), the physics world's and the vehicle's control loop's.
  uint64_t servo_ticks = 0;
  /// Every arm's servo ticks, summed (a tick of each arm is one servo
  /// message in a session file); commands sent and states taken by the link.
  uint64_t servo_arm_ticks = 0;
  uint64_t commands_sent = 0;
  uint64_t states_received = 0;
  uint64_t physics_ticks = 0;
  uint64_t vehicle_ticks = 0;
  /// The reality the simulated vehicle ran (its name and seed, from its
  /// truth record's header after the run; "" when it wrote none).
  std::string reality;
  uint64_t reality_seed = 0;
  /// Every error bit the vehicle's servo controller reported over the run
  /// (the Maestro's register, controller_errors.hpp; 0: none, or no such
  /// controller).
  uint16_t controller_errors = 0;
};

/// Runs one lap (or until the cap, the time limit, a lost vehicle or device,
/// the person's abort, or `interrupted`): the session loop with one vehicle,
/// driven all along (a fleet's, fleet.hpp, drives several in turns). Throws
/// ConfigError / std::runtime_error for parts that cannot be set up (before
/// anything moves).
SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted);

}  // namespace haptel::mediator
