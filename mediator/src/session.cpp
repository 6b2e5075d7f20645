// The one session loop: `haptel run`'s single vehicle, driven all along,
// and a fleet's vehicles (`haptel run --fleet`), driven in turns
// (fleet_turns.hpp), go through the same steps over the same per-vehicle
// parts (VehicleRun), whatever their family (FamilySession).
#include "haptel/mediator/session.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <memory>
#include <stdexcept>
#include <thread>

#include "family_session.hpp"
#include "fleet_turns.hpp"
#include "haptel/config/link.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/notice_log.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/view/head_source.hpp"
#include "haptel/view/sdl_input.hpp"
#include "haptel/view/view_record.hpp"
#include "simulated_time.hpp"

namespace haptel::mediator {

namespace {

/// The session thread's SCHED_FIFO priority while its loop runs in real
/// time: below the physics thread's (config/physics.yaml, 70) and the servo
/// loop's (80), whose steps it reads, above every normal thread. On a loaded
/// host a normal session thread waited tens to hundreds of milliseconds for
/// the CPU: commands late by as much (issue 36: input to command p95) and,
/// past 200 ms, the vehicle's watchdog stopping it.
constexpr int kSessionPriority = 60;
/// A session tick this many periods long gives the real-time priority up.
constexpr int64_t kLoseRealtimePeriods = 10;

}  // namespace

std::string ToString(Outcome outcome) {
  switch (outcome) {
    case Outcome::kCompleted:
      return "completed";
    case Outcome::kLapCap:
      return "lap cap";
    case Outcome::kTimeLimit:
      return "time limit";
    case Outcome::kVehicleLost:
      return "vehicle lost";
    case Outcome::kVehicleDidNotStart:
      return "vehicle did not start";
    case Outcome::kDeviceLost:
      return "device lost";
    case Outcome::kAborted:
      return "aborted";
    case Outcome::kInterrupted:
      return "interrupted";
    case Outcome::kCrashed:
      return "crashed";
    case Outcome::kConflict:
      return "conflict";
    case Outcome::kRefused:
      return "refused";
    case Outcome::kLostControl:
      return "lost control";
  }
  return "unknown";
}

int ExitCode(Outcome outcome) {
  switch (outcome) {
    case Outcome::kCompleted:
      return 0;
    case Outcome::kVehicleLost:
    case Outcome::kVehicleDidNotStart:
    case Outcome::kDeviceLost:
      return 3;
    case Outcome::kConflict:
    case Outcome::kRefused:
    case Outcome::kLostControl:
      return 2;
    default:
      return 1;
  }
}

namespace {

/// How long the view says that the run's head is not the one it asked for.
constexpr double kHeadFallbackShown_s = 10.0;

/// A simulated-time run's loops, counted on its clock (no thread measured
/// them: each kept its rate exactly), and its speed-up over real time.
void RecordSimulatedFigures(const SimulatedTime& simulated, int64_t session_ns, int64_t wall_ns,
                            SessionResult& result) {
  RunRecord& rec = result.record;
  const double session_s = NsToS(session_ns);
  result.simulated_s = session_s;
  result.wall_s = NsToS(wall_ns);
  result.servo_ticks = simulated.servo_ticks();
  result.physics_ticks = simulated.physics_ticks();
  result.vehicle_ticks = simulated.vehicle_ticks();
  rec.speedup = result.wall_s > 0.0 ? session_s / result.wall_s : 0.0;
  if (session_s > 0.0) rec.servo_rate_hz = static_cast<double>(simulated.servo_ticks()) / session_s;
  rec.servo_period_p99_us = simulated.servo_period_s() * 1e6;
  if (simulated.physics_ticks() > 0 && session_s > 0.0) {
    result.physics_rate_hz = static_cast<double>(simulated.physics_ticks()) / session_s;
    result.physics_period_p99_us = simulated.physics_period_s() * 1e6;
    rec.physics_rate_hz = result.physics_rate_hz;
  }
}

/// The process's CPU time (every thread), s.
double ProcessCpuS() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec) * 1e-6;
}

/// "fleet <name> <started, UTC>": the name the rows of one fleet run share.
std::string FleetRunName(const std::string& fleet, int64_t wall_ns) {
  const std::time_t seconds = static_cast<std::time_t>(wall_ns / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return "fleet " + fleet + " " + text;
}

/// The session loop over the run's vehicles: one, driven all along (a
/// single run), or a fleet's, driven in turns (FleetTurns). Its steps: the
/// set-up (SetUp: the haptic side, each vehicle's family part, link and
/// health, the view); each tick (Loop), the operator side, every vehicle's
/// states and health (WatchVehicles), the fleet's turn, the commands
/// (CommandVehicles), the view (FeedView), the courses' and the session's
/// limits (CheckLimits), the progress lines (LogProgress); and the end
/// (Finish: made safe, stopped, recorded). Each vehicle's result is in its
/// VehicleRun's `out`.
class SessionLoop {
 public:
  /// `fleet` and `fleet_result`: a fleet's run (both null: one vehicle).
  SessionLoop(const std::vector<const SessionSetup*>& setups, const FleetConfig* fleet,
              FleetResult* fleet_result, const std::atomic<bool>& interrupted);

  void Run() {
    if (SetUp()) Finish(Loop());
  }
  std::vector<std::unique_ptr<VehicleRun>>& vehicles() { return vehicles_; }

 private:
  /// False when interrupted before anything started (recorded so).
  bool SetUp();
  void AbandonSetup();
  void Link(VehicleRun& vehicle);
  void SayLinked(const VehicleRun& vehicle) const;
  void OpenView();
  /// The head source the run's `head:` names (the mouse when it cannot have
  /// it, said on screen and in the log).
  void MakeHead();
  /// The session file's view channel: the view's set-up now, and through
  /// `options`' tap every frame it draws at the MP4's rate
  /// (view/view_record.hpp), so that haptel replay draws them again.
  void TapView(view::ViewOptions& options, std::shared_ptr<const view::TrackMap> map);
  /// The loops until the session's end (none: every course of a fleet is over).
  std::optional<LoopEnd> Loop();
  /// Sleeps until the next tick (in simulated time: steps every part to it).
  void Pace();
  /// Until the next tick, the driven interface's command is looked at every
  /// kBetweenTicks_ns, while its family part asks (FamilySession::
  /// CommandBetweenTicks): a person's input reaches the vehicle within a
  /// physics step of moving the control, not at the next 10-ms tick.
  void CommandBetweenTicks();
  /// The physics world's step (config/physics.yaml's 1000 Hz): the controls
  /// move no more often.
  static constexpr int64_t kBetweenTicks_ns = 1'000'000;
  std::optional<LoopEnd> WatchVehicles(int64_t now_ns, double t_s);
  std::optional<LoopEnd> CommandVehicles(const interfaces::InputState& person, int64_t now_ns,
                                         double t_s, double dt_s);
  /// Whether the operator engages the interface `vehicle` is driven with
  /// now (engagement.hpp); a change is said, the time disengaged counted.
  bool Engage(VehicleRun& vehicle, int64_t now_ns, double t_s, double dt_s);
  void FeedView(int64_t now_ns, double t_s);
  /// The session file's records of this tick (with one): the interfaces'
  /// switches and engagement, the lap's start and contacts, the force
  /// fields as they change, the ghost.
  void FeedSessionFile(int64_t now_ns, double t_s);
  /// The part of it the records hold (switches, contacts, the lap's start):
  /// also at the end, when the parts are stopped.
  void FileRecords(int64_t now_ns, double t_s);
  /// The session file's last records (the lap's gates and end) and its close.
  void CloseSessionFile();
  std::optional<LoopEnd> CheckLimits(double t_s);
  void LogProgress(int64_t now_ns, double t_s);
  /// A vehicle's end: the session's for a single run; a fleet's turns say.
  std::optional<LoopEnd> OnVehicleEnd(VehicleRun& vehicle, LoopEnd end);
  void Finish(const std::optional<LoopEnd>& end);
  void StopLinks();

  const SessionSetup& first_;  ///< the device, operator, view and limits are the first's
  const FleetConfig* fleet_;
  FleetResult* fleet_result_;
  const std::atomic<bool>& interrupted_;
  const int64_t wall_start_ns_;
  const double cpu_start_s_;
  // Declared in the order they are built; destroyed the other way round
  // (the simulated clock last, back to the real clock).
  std::unique_ptr<SimulatedTime> simulated_;
  /// The session file (none without SessionSetup::session_file): made
  /// before the parts it taps, closed after they stopped.
  std::unique_ptr<record::SessionRecorder> session_file_;
  std::unique_ptr<HapticSide> haptic_;
  interfaces::InputBox input_;
  std::vector<std::unique_ptr<VehicleRun>> vehicles_;
  std::unique_ptr<FleetTurns> turns_;  ///< a fleet's; none for one vehicle
  /// The session file's view channel (with a session file and a view):
  /// the view's tap, outliving the view that calls it.
  std::unique_ptr<view::ViewFrameEncoder> view_tap_;
  std::unique_ptr<SessionView> view_;
  std::unique_ptr<view::InputPump> pump_;
  /// Where the person's head looks (the pan/tilt camera follows it): the
  /// InputState's head_pan/head_tilt each tick are this source's.
  std::unique_ptr<view::HeadSource> head_;
  NoticeLog head_notice_;
  /// Said on screen for the first seconds: the source the run asked for is
  /// not the one it got (view::MadeHeadSource::fallback).
  std::string head_fallback_;
  /// The head's pose, applied to what the person does (the pan/tilt
  /// camera's source), and what it says logged once it settles.
  void TurnHead(interfaces::InputState& person, double t_s);
  Engagement engagement_;  ///< the person's, with whichever vehicle they drive
  /// What the progress log said of it last (as if engaged before the start:
  /// a run that starts without a hand says so).
  Disengaged engagement_said_ = Disengaged::kNone;
  int64_t t0_ = 0;
  int64_t period_ns_ = 0;
  int64_t next_tick_ = 0;
  int64_t next_progress_ns_ = 0;
  int64_t next_live_ns_ = 0;
  uint64_t pictures_seen_ = 0;
  /// What the session file has of each vehicle's record, and the fields.
  struct SessionFileSeen {
    size_t switches = 0;
    size_t contacts = 0;
    bool lap_started = false;
    /// Each hand's hold on its control as filed (a cockpit's: the left
    /// hand's on the wheel, the right's on the lever).
    std::array<bool, haptics::kSides> holds{};
  };
  std::vector<SessionFileSeen> file_seen_;
  /// A vehicle's hands' grasps and releases of its controls (with any) as
  /// they change: interface events "grasp", "release" (side: the hand;
  /// text: the control).
  void FileGrasps(const VehicleRun& v, SessionFileSeen& seen, int32_t vehicle, int64_t now_ns,
                  double t_s);
  std::array<haptics::ForceField, haptics::kSides> fields_seen_{};
  std::array<bool, haptics::kSides> field_said_{};
  Disengaged engagement_filed_ = Disengaged::kNone;
  double last_t_ = 0.0;
  double loop_cpu_start_s_ = 0.0;  ///< the process's, when the loop began
};

SessionLoop::SessionLoop(const std::vector<const SessionSetup*>& setups, const FleetConfig* fleet,
                         FleetResult* fleet_result, const std::atomic<bool>& interrupted)
    : first_(*setups.at(0)),
      fleet_(fleet),
      fleet_result_(fleet_result),
      interrupted_(interrupted),
      wall_start_ns_(RealMonotonicNs()),
      cpu_start_s_(ThreadCpuSeconds()) {
  // In simulated time the clock comes first: every stamp the set-up takes
  // is on it. It steps one robot in this process: a single run's.
  if (first_.simulated_time) {
    if (setups.size() != 1) throw std::invalid_argument("simulated time runs one vehicle");
    simulated_ = std::make_unique<SimulatedTime>(first_);
  }
  const int64_t started_wall_ns = WallNs();
  if (fleet_result_) fleet_result_->fleet_run = FleetRunName(fleet_->name, started_wall_ns);
  for (const SessionSetup* s : setups) {
    auto v = std::make_unique<VehicleRun>(*s);
    RunRecord& rec = v->out.result.record;
    rec.started_wall_ns = started_wall_ns;
    // The rows of one fleet run share its name.
    rec.config_name = fleet_result_ ? fleet_result_->fleet_run : s->run.name;
    rec.vehicle = s->vehicle.name;
    rec.vehicle_kind = s->vehicle.kind;
    rec.link_fault = s->run.link.fault.enabled ? LinkFaultText(s->run.link.fault) : "";
    rec.operator_kind = s->operator_kind;
    rec.device = s->device.driver;
    vehicles_.push_back(std::move(v));
  }
}

bool SessionLoop::SetUp() {
  // The haptic side first, then each vehicle's family part (its world, its
  // interfaces, its operator): the hands are held before anything moves.
  if (!first_.session_file.file.empty()) {
    session_file_ = std::make_unique<record::SessionRecorder>(first_.session_file);
    file_seen_.resize(vehicles_.size());
  }
  haptic_ = std::make_unique<HapticSide>(first_.device, first_.calibration, first_.gravity,
                                         first_.run.op, first_.trace);
  if (session_file_) haptic_->SetServoTap(session_file_.get());
  for (auto& v : vehicles_) {
    v->family = MakeFamilySession(v->setup, *haptic_, input_, interrupted_, v->out.result.record);
    if (interrupted_.load()) break;
  }
  if (interrupted_.load()) {
    AbandonSetup();
    return false;
  }
  if (!simulated_) {
    // In simulated time these are stepped by the session's own thread (AdvanceTo).
    haptic_->Start(first_.progress);
    for (auto& v : vehicles_) v->family->Start(*haptic_);
  }
  if (fleet_) {
    std::vector<VehicleRun*> runs;
    for (auto& v : vehicles_) runs.push_back(v.get());
    turns_ = std::make_unique<FleetTurns>(*fleet_, std::move(runs), *haptic_, *fleet_result_);
  }
  for (auto& v : vehicles_) Link(*v);
  OpenView();
  MakeHead();
  // A person's controller without a view: a thread of its own polls it.
  const bool gamepad_head = head_->kind() == HeadSourceKind::kGamepad;
  if (!view_ && (gamepad_head || std::any_of(vehicles_.begin(), vehicles_.end(), [](const auto& v) {
                   return v->family->UsesGamepad();
                 }))) {
    pump_ = std::make_unique<view::InputPump>(input_);
  }
  if (turns_) turns_->Begin(view_.get(), input_.Load().vehicle_requests);

  t0_ = MonotonicNs();
  loop_cpu_start_s_ = ProcessCpuS();
  const RunConfig& run = first_.run;
  for (auto& v : vehicles_) {
    v->health = std::make_unique<VehicleHealth>(
        v->setup.vehicle.name, run.link.domain_id, v->link->session(), v->link->command_writer(),
        run.vehicle_timeout_s, VehicleHealth::kStartupTimeout_s, v->link->pid());
    v->trace = std::make_unique<RunTrace>(v->out.result.record);
    v->out.result.record.path.reserve(16384);
    // The view's loop is watched with the first vehicle's (one window for all).
    v->watch = std::make_unique<LoopWatch>(*haptic_, v->family->physics(), *v->link,
                                           v == vehicles_.front() ? view_.get() : nullptr, t0_);
  }
  period_ns_ = static_cast<int64_t>(1e9 / run.session_rate_hz);
  next_tick_ = t0_;
  next_progress_ns_ = t0_ + SToNs(2.0);
  next_live_ns_ = t0_;
  return true;
}

// During the set-up (thousands of scene bodies take a while): nothing has
// started yet, nothing is spawned; the run ends here, recorded.
void SessionLoop::AbandonSetup() {
  const LoopEnd end{Outcome::kInterrupted, "interrupted by the operator during the set-up"};
  if (fleet_result_) {
    fleet_result_->outcome = end.outcome;
    fleet_result_->message = end.message;
  }
  for (auto& v : vehicles_) {
    SessionResult& r = v->out.result;
    r.outcome = end.outcome;
    r.message = end.message;
    r.record.outcome = ToString(r.outcome);
    if (v->family) v->family->AbandonSetup(r);
  }
}

// The vehicle: spawned (or attached to) and linked, on the run's domain.
void SessionLoop::Link(VehicleRun& v) {
  VehicleLinkOptions options;
  options.vehicle = v.setup.vehicle;
  options.link = v.setup.run.link;
  options.track_file = v.family->world_file();
  options.program = v.setup.vehicle_program;
  options.decode_video = first_.run.video_decode && DecodesVideo(first_.view);
  options.publish_selected = turns_ != nullptr;  // who commands each of a fleet's vehicles
  options.tap = session_file_.get();
  if (simulated_) {
    options.program.clear();
    options.in_process_robot = [simulated = simulated_.get()](const msg::TreadCommand& command) {
      simulated->OnCommand(command);
    };
  }
  v.link = std::make_unique<VehicleLink>(options);
  v.out.result.record.vehicle_pid = v.link->pid();
  SayLinked(v);
}

void SessionLoop::SayLinked(const VehicleRun& v) const {
  if (!first_.progress) return;
  const std::string& name = v.setup.vehicle.name;
  const std::string& kind = v.setup.vehicle.kind;
  const int64_t pid = v.link->pid();
  if (fleet_) {
    log::Info("fleet '" + fleet_->name + "': vehicle '" + name + "' (" + kind + ") " +
              (pid != 0 ? "started, pid " + std::to_string(pid)
                        : std::string("attaching on domain ") +
                              std::to_string(first_.run.link.domain_id) +
                              " (a vehicle already running there)"));
    return;
  }
  if (v.setup.attach) {
    log::Info("attached to vehicle '" + name + "' on domain " +
              std::to_string(v.setup.run.link.domain_id) + " (session " +
              std::to_string(v.link->session()) + "): spawning none");
  }
  if (simulated_) {
    log::Info("vehicle '" + name + "' (" + kind +
              ") stepped in this process, on the simulated clock");
  }
  if (pid != 0)
    log::Info("vehicle '" + name + "' (" + kind + ") started, pid " + std::to_string(pid));
}

// The view, when something shows it (a window, or offscreen for the MP4):
// each vehicle's parts, the driven one's on the big screen and, in a fleet,
// every vehicle's video on its tile.
void SessionLoop::OpenView() {
  if (first_.view == ViewKind::kNone) return;
  view::ViewOptions options = ViewOptionsFor(first_);
  if (fleet_) options.title = "Haptel - fleet " + fleet_->name;
  std::vector<SessionView::Parts> parts;
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    VehicleRun& v = *vehicles_[i];
    SessionView::Parts p;
    p.hal = &haptic_->hal();
    p.physics_config = &v.setup.physics;  // the hands' size, with or without a world
    p.video = &v.link->video();
    view::ViewOptions own = options;  // the window is the first vehicle's: its screen placement
    v.family->ConfigureView(p, i == 0 ? options : own);
    parts.push_back(p);
  }
  if (session_file_) TapView(options, parts.front().map);
  view_ = std::make_unique<SessionView>(options, std::move(parts), input_);
}

void SessionLoop::TapView(view::ViewOptions& options, std::shared_ptr<const view::TrackMap> map) {
  record::SessionRecorder& file = *session_file_;
  const int setup_channel =
      file.AddOwnChannel(view::kViewSetupTopic, view::kViewSetupSchemaName, view::kViewRecordIdl);
  const int frame_channel =
      file.AddOwnChannel(view::kViewFrameTopic, view::kViewFrameSchemaName, view::kViewRecordIdl);
  if (setup_channel < 0 || frame_channel < 0) return;  // the recorder says why in its report
  view_tap_ = view::StartViewRecord(
      options, std::move(map),
      [&file, setup_channel](const uint8_t* data, size_t size) {
        file.OnSample(setup_channel, MonotonicNs(), nullptr, data, size);
      },
      [&file, frame_channel](const uint8_t* data, size_t size) {
        file.OnSample(frame_channel, MonotonicNs(), nullptr, data, size);
      });
}

std::optional<LoopEnd> SessionLoop::Loop() {
  // Simulated time never sleeps: a real-time thread there would hold a core.
  std::optional<RealtimeWhile> realtime;
  if (!simulated_) realtime.emplace(kSessionPriority);
  for (;;) {
    Pace();
    const int64_t now = MonotonicNs();
    const double t = NsToS(now - t0_);
    const double dt = t - last_t_;
    last_t_ = t;
    if (auto end = CheckOperatorSide(interrupted_, *haptic_, first_.device.name)) return end;
    interfaces::InputState person = input_.Load();
    if (person.quit) return LoopEnd{Outcome::kAborted, "the view was closed"};
    TurnHead(person, t);
    if (auto end = WatchVehicles(now, t)) return end;
    if (turns_ && !turns_->Turn(person, now, t)) return std::nullopt;  // every course is over
    if (auto end = CommandVehicles(person, now, t, dt)) return end;
    FeedView(now, t);
    if (session_file_) FeedSessionFile(now, t);
    if (auto end = CheckLimits(t)) return end;
    LogProgress(now, t);
    // A tick of ten periods is no real-time work: at SCHED_FIFO it would
    // hold a core from the view, DDS's threads and the host. Given up for
    // good, as the physics thread gives it up (core/periodic_thread.hpp).
    // So is a loop ten periods behind its schedule: Pace() no longer sleeps
    // then, and ticks back to back at SCHED_FIFO held a core each (two runs'
    // session threads at 45-87 % beside the loaded suite's stalled tests).
    const int64_t behind_ns = now - (next_tick_ - period_ns_);
    if (realtime && (MonotonicNs() - now > kLoseRealtimePeriods * period_ns_ ||
                     behind_ns > kLoseRealtimePeriods * period_ns_)) {
      realtime.reset();
    }
  }
}

void SessionLoop::MakeHead() {
  view::MadeHeadSource made = view::MakeHeadSource(first_.run.head, input_.Load());
  head_ = std::move(made.source);
  head_fallback_ = std::move(made.fallback);
  if (!head_fallback_.empty()) log::Warn(head_fallback_);
  for (auto& v : vehicles_) {
    v->out.result.head_source = ToString(head_->kind());
    v->out.result.head_fallback = head_fallback_;
  }
}

void SessionLoop::TurnHead(interfaces::InputState& person, double t) {
  const view::HeadPose pose = head_->Update(t, person);
  person.head_pan = pose.pan;
  person.head_tilt = pose.tilt;
  if (const char* notice = head_notice_.Update(t, head_->Notice())) log::Warn(notice);
}

void SessionLoop::Pace() {
  if (simulated_) {
    const VehicleRun& v = *vehicles_.front();
    simulated_->AdvanceTo(next_tick_, *haptic_, v.family->physics(), *v.link);
  } else {
    CommandBetweenTicks();
    SleepUntilNs(next_tick_);
  }
  next_tick_ += period_ns_;
}

void SessionLoop::CommandBetweenTicks() {
  // A single run's vehicle only: a fleet's turns hand the person over at
  // the tick. Simulated time has nothing between its ticks.
  if (turns_ || vehicles_.size() != 1) return;
  VehicleRun& v = *vehicles_.front();
  for (int64_t at = MonotonicNs() + kBetweenTicks_ns; at < next_tick_; at += kBetweenTicks_ns) {
    SleepUntilNs(at);
    if (v.lost || !v.health->up()) return;
    const int64_t now = MonotonicNs();
    if (!v.family->CommandBetweenTicks(NsToS(now - t0_), now, *haptic_, *v.link)) return;
  }
}

// Every vehicle's health and states, driven or not: a fleet's operator
// keeps an eye on all of them, and each one's lap and trace go on.
std::optional<LoopEnd> SessionLoop::WatchVehicles(int64_t now, double t) {
  for (auto& vp : vehicles_) {
    VehicleRun& v = *vp;
    if (v.lost) continue;
    std::optional<LoopEnd> end = v.health->CheckProcess(*v.link, now);
    if (!end) {
      v.family->Drain(*v.link, *v.health, *haptic_, *v.trace, t0_);
      end = v.health->CheckStates(*v.link, now, t);
    }
    if (!end) continue;
    if (auto session_end = OnVehicleEnd(v, std::move(*end))) return session_end;
  }
  return std::nullopt;
}

// The operator's vehicle is commanded by its family's interface; a fleet's
// others are held safe by the turns.
std::optional<LoopEnd> SessionLoop::CommandVehicles(const interfaces::InputState& person,
                                                    int64_t now, double t, double dt) {
  if (turns_) turns_->TickInterfaces(t, person);
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    VehicleRun& v = *vehicles_[i];
    if (v.lost) continue;
    if (!turns_ || turns_->Operated(i, now, t, dt)) {
      const bool engaged = Engage(v, now, t, dt);
      if (auto end = v.family->Command(t, now, person, v.health->up(), engaged, *haptic_, *v.link))
        return end;
    }
    if (const SessionPhysics* physics = v.family->physics(); physics != v.watch->physics()) {
      // A world built for an interface just asked for: watched and drawn from now on.
      v.watch->AddPhysics(physics, now);
      if (view_) view_->SetPhysics(static_cast<int>(i), physics);
    }
  }
  if (turns_) turns_->Settle(t);
  return std::nullopt;
}

// Disengaged, the vehicle gets a zero command; the time it was up and not
// engaged is the run's disengaged_s.
bool SessionLoop::Engage(VehicleRun& v, int64_t now, double t, double dt) {
  const bool engaged = engagement_.Update(haptic_->hal(), v.family->Rest());
  haptic_->RecordEngaged(now, engaged);
  if (!engaged && v.health->up()) v.out.result.record.disengaged_s += dt;
  if (engagement_.why() != engagement_said_ && first_.progress) {
    engagement_said_ = engagement_.why();
    char line[160];
    std::snprintf(
        line, sizeof line, "%6.1f s  %s: %s", t, engaged ? "engaged" : "not engaged",
        engaged ? "the vehicle takes the interface's command" : ToString(engagement_.why()));
    log::Info(line);
  }
  return engaged;
}

// The view's next frames: the driven vehicle's overlay, gaze and ghost on
// the big screen (a fixed gaze and no ghost when it has none), and a
// fleet's tiles; twice a second, whoever watches the run live (a study's
// console). The overlays are made every tick: they notice contacts by
// their edges. Allocation-free: overlays and tiles are flat.
void SessionLoop::FeedView(int64_t now, double t) {
  const bool live_due = (first_.on_live || first_.on_picture) && now >= next_live_ns_;
  if (live_due) next_live_ns_ = now + SToNs(0.5);
  if (view_ || first_.on_live) {
    const int shown = turns_ ? turns_->driven() : 0;
    for (size_t i = 0; i < vehicles_.size(); ++i) {
      VehicleRun& v = *vehicles_[i];
      const bool up = !v.lost && v.health->up();
      v.overlay = v.family->Overlay(t, up, v.trace->touching());
      // Not engaged: said over the interface's help (a switch or a wait says more).
      if (static_cast<int>(i) == shown && up && !engagement_.engaged() &&
          !v.family->SwitchingInterface()) {
        std::snprintf(v.overlay.message, sizeof v.overlay.message, "%s", engagement_.Line());
      }
      // The head's trouble (a tracker lost) over the rest; the source the
      // run did not get, for its first seconds.
      const char* head = head_->Notice();
      if (head == nullptr && !head_fallback_.empty() && t < kHeadFallbackShown_s)
        head = head_fallback_.c_str();
      if (static_cast<int>(i) == shown && head != nullptr)
        std::snprintf(v.overlay.message, sizeof v.overlay.message, "%s", head);
    }
    if (view_ && shown >= 0) {
      VehicleRun& v = *vehicles_[static_cast<size_t>(shown)];
      view_->Publish(v.overlay);
      view_->Publish(v.family->Gaze().value_or(view::Gaze{}));
      view_->Publish(v.family->Prediction(t).value_or(view::Prediction{}));
    }
    if (view_ && turns_) turns_->PublishTiles(*view_, t);
    if (first_.on_live && live_due) first_.on_live(vehicles_.front()->overlay);
  }
  if (first_.on_picture && live_due) {
    const video::VideoReceiver& video = vehicles_.front()->link->video();
    const uint64_t frames = video.Stats().frames;
    if (frames != pictures_seen_) {
      // Frames can be counted before one decodes (an H.264 stream's first
      // key frame still on its way): no picture yet is tried again next time.
      std::vector<uint8_t> jpeg = video.LatestPicture();
      if (!jpeg.empty()) {
        pictures_seen_ = frames;
        first_.on_picture(std::move(jpeg), frames);
      }
    }
  }
}

// Each course's own end (completed, crashed) and cap, then the session's
// time limit. A single run's lap clock starts at its start line and its
// limits are the session's (CheckLimits); a fleet's vehicle's cap counts
// the time it was driven.
std::optional<LoopEnd> SessionLoop::CheckLimits(double t) {
  for (auto& vp : vehicles_) {
    VehicleRun& v = *vp;
    if (v.done) continue;
    std::optional<LoopEnd> end = v.family->LapEnd();
    if (!end && turns_) end = turns_->CapEnd(v);
    if (!end && !turns_) {
      end = mediator::CheckLimits(t, v.family->lap_start_s(), v.setup.time_limit_s,
                                  v.setup.lap_limit_s, v.family->lap_cap_s());
    }
    if (!end) continue;
    if (auto session_end = OnVehicleEnd(v, std::move(*end))) return session_end;
  }
  return mediator::CheckLimits(t, std::nullopt, first_.time_limit_s, 0.0,
                               std::numeric_limits<double>::infinity());
}

void SessionLoop::LogProgress(int64_t now, double t) {
  if (now < next_progress_ns_) return;
  next_progress_ns_ += SToNs(2.0);
  // In simulated time every loop keeps its rate by construction (no thread
  // measures it). The first vehicle's watch says the shared loops' (servo, view).
  std::vector<std::string> short_loops;
  if (!simulated_) {
    for (auto& v : vehicles_) {
      std::vector<std::string> lines = v->watch->EndInterval(now);
      if (v == vehicles_.front()) short_loops = std::move(lines);
    }
  }
  if (!first_.progress) return;
  if (turns_) {
    for (const std::string& loop : short_loops) log::Warn(loop);
    turns_->LogProgress(t);
    return;
  }
  const VehicleRun& v = *vehicles_.front();
  v.family->LogProgress(t, *v.link, v.out.result.record.distance_m);
  for (const std::string& loop : short_loops) log::Warn(loop);
  const std::string counters = NonZeroCounters(v.watch->Counters());
  if (!counters.empty()) log::Info("         counters: " + counters);
}

std::optional<LoopEnd> SessionLoop::OnVehicleEnd(VehicleRun& v, LoopEnd end) {
  if (turns_) return turns_->OnVehicleEnd(v, std::move(end));
  return end;
}

void SessionLoop::Finish(const std::optional<LoopEnd>& end) {
  // Who was not done ends as the session did.
  if (end) {
    for (auto& v : vehicles_) {
      if (v->done) continue;
      mediator::Finish(v->out.result, *end, v->family->MadeSafe());
      v->done = true;
    }
  }
  const int64_t end_ns = MonotonicNs();
  if (fleet_result_) {
    fleet_result_->operator_cpu_share =
        (ProcessCpuS() - loop_cpu_start_s_) / std::max(NsToS(end_ns - t0_), 1e-3);
  }
  if (!simulated_) {
    for (auto& v : vehicles_) {
      const std::vector<std::string> short_loops = v->watch->EndInterval(end_ns);
      // A single run says its last stretch's short loops; a fleet's progress lines only.
      if (first_.progress && !turns_) {
        for (const std::string& loop : short_loops) log::Warn(loop);
      }
    }
  }

  // Make safe: forces to zero (a physics world's leave the HAL at once too,
  // whatever its step is doing), every vehicle stopped or at neutral.
  haptic_->hal().ZeroForces();
  for (auto& v : vehicles_) {
    v->family->RequestStop();
    if (!v->lost) v->link->SendSafe();
  }
  if (simulated_) simulated_->Stop();
  // The view's figures are the first vehicle's record's (one window for all).
  if (view_) StopAndRecord(*view_, vehicles_.front()->out.result);
  const double end_s = NsToS(end_ns - t0_);
  for (auto& v : vehicles_) {
    v->family->Finish(v->out.result, first_.progress);
    if (turns_) continue;  // a fleet's laps count the time each was driven, not the session's
    // The lap's clock and the approach's are kept apart: a run that never
    // reached the line was all approach. A lap stopped by a limit ran until
    // the run ended, on the same clock as the limits (the last state may be
    // a few ms older): a lap stopped by its cap shows the whole cap.
    RunRecord& rec = v->out.result.record;
    const std::optional<double> lap_start = v->family->lap_start_s();
    rec.approach_s = lap_start.value_or(end_s);
    const Outcome outcome = v->out.result.outcome;
    if (lap_start && (outcome == Outcome::kTimeLimit || outcome == Outcome::kLapCap))
      rec.lap_time_s = std::max(rec.lap_time_s, end_s - *lap_start);
  }
  haptic_->Stop();
  if (pump_) pump_->Stop();
  StopLinks();
  const haptics::DeviceUseReport use = haptic_->UseReport();
  for (auto& v : vehicles_) {
    RecordLinkFigures(*haptic_, *v->link, v->out.result);
    v->watch->Finish(v->out.result.record);
    v->out.result.record.pseudo_haptic_gain_mean = use.pseudo_haptic_gain_mean;
    v->out.result.record.ff_effects_played = static_cast<int64_t>(use.ff_effects_played);
  }
  if (simulated_) {
    SessionResult& result = vehicles_.front()->out.result;
    RecordSimulatedFigures(*simulated_, end_ns - t0_, RealMonotonicNs() - wall_start_ns_, result);
    result.cpu_s = ThreadCpuSeconds() - cpu_start_s_;
  }
  if (turns_) turns_->Finish(end, *haptic_);
  if (session_file_) CloseSessionFile();
}

void SessionLoop::FileRecords(int64_t now, double t) {
  record::SessionRecorder& file = *session_file_;
  using record::SessionEvent;
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    VehicleRun& v = *vehicles_[i];
    SessionFileSeen& seen = file_seen_[i];
    const RunRecord& rec = v.out.result.record;
    for (; seen.switches < rec.switches.size(); ++seen.switches) {
      const record::SwitchRecord& s = rec.switches[seen.switches];
      const std::string text = s.from + " -> " + s.to;
      file.InterfaceEvent(
          SessionEvent::Make(now, t, "switch", static_cast<int32_t>(i), 255, 0.0, text.c_str()));
    }
    for (; seen.contacts < rec.contacts.size(); ++seen.contacts) {
      const record::ContactPoint& c = rec.contacts[seen.contacts];
      file.LapEvent(
          SessionEvent::Make(now, c.t_s, "contact", -1, 255, 0.0, v.setup.vehicle.name.c_str()));
    }
    if (!seen.lap_started && v.family->lap_start_s()) {
      seen.lap_started = true;
      file.LapEvent(SessionEvent::Make(now, *v.family->lap_start_s(), "start", -1, 255, 0.0,
                                       v.setup.vehicle.name.c_str()));
    }
  }
}

void SessionLoop::FeedSessionFile(int64_t now, double t) {
  FileRecords(now, t);
  record::SessionRecorder& file = *session_file_;
  using record::SessionEvent;
  for (size_t i = 0; i < vehicles_.size(); ++i) {
    VehicleRun& v = *vehicles_[i];
    if (const std::optional<view::Prediction> p = v.family->Prediction(t); p && p->shown) {
      record::SessionGhost g;
      g.t_ns = now;
      g.valid = true;
      g.x = p->predicted.x;
      g.y = p->predicted.y;
      g.z = p->predicted.z;
      g.heading = p->predicted.heading;
      g.reported_x = p->reported.x;
      g.reported_y = p->reported.y;
      g.reported_z = p->reported.z;
      g.delay_s = p->one_way_delay_s;
      file.Ghost(g);
    }
    FileGrasps(v, file_seen_[i], static_cast<int32_t>(i), now, t);
  }
  if (engagement_.why() != engagement_filed_) {
    engagement_filed_ = engagement_.why();
    const bool engaged = engagement_.engaged();
    file.InterfaceEvent(SessionEvent::Make(now, t, engaged ? "engaged" : "disengaged", -1, 255, 0.0,
                                           engaged ? "" : ToString(engagement_.why())));
  }
  // The fields as the interfaces set them (the servo loop's set-points): a
  // change is filed, and a wall going up is an interface event.
  for (const haptics::Side side : {haptics::Side::kLeft, haptics::Side::kRight}) {
    haptics::ForceSetpoint sp;
    if (!haptic_->hal().TrySetpoint(side, sp)) continue;
    const auto k = static_cast<size_t>(haptics::Index(side));
    if (field_said_[k] && std::memcmp(&sp.field, &fields_seen_[k], sizeof sp.field) == 0) continue;
    if (sp.field.wall_active && (!field_said_[k] || !fields_seen_[k].wall_active)) {
      file.InterfaceEvent(SessionEvent::Make(now, t, "wall", -1, static_cast<uint8_t>(k)));
    }
    fields_seen_[k] = sp.field;
    field_said_[k] = true;
    file.Field(now, static_cast<uint8_t>(k), sp.field);
  }
}

void SessionLoop::FileGrasps(const VehicleRun& v, SessionFileSeen& seen, int32_t vehicle,
                             int64_t now, double t) {
  const SessionPhysics* physics = v.family->physics();
  if (physics == nullptr || !physics->port) return;  // no controls to grasp
  const interfaces::CockpitControls controls = physics->port->Controls();
  const std::array<bool, haptics::kSides> holds{controls.wheel_held, controls.throttle_held};
  static constexpr std::array<const char*, haptics::kSides> kControl{"wheel", "lever"};
  for (size_t k = 0; k < holds.size(); ++k) {
    if (holds[k] == seen.holds[k]) continue;
    seen.holds[k] = holds[k];
    session_file_->InterfaceEvent(record::SessionEvent::Make(now, t, holds[k] ? "grasp" : "release",
                                                             vehicle, static_cast<uint8_t>(k), 0.0,
                                                             kControl[k]));
  }
}

void SessionLoop::CloseSessionFile() {
  record::SessionRecorder& file = *session_file_;
  using record::SessionEvent;
  const int64_t now = MonotonicNs();
  const double t = NsToS(now - t0_);
  if (t0_ != 0) {
    FileRecords(now, t);
    for (auto& v : vehicles_) {
      const RunRecord& rec = v->out.result.record;
      const char* name = v->setup.vehicle.name.c_str();
      for (const record::GateSplit& split : rec.splits) {
        if (split.passed)
          file.LapEvent(SessionEvent::Make(now, t, "gate", split.gate, 255, split.split_s, name));
      }
      const Outcome outcome = v->out.result.outcome;
      const char* kind = outcome == Outcome::kCompleted ? "finish"
                         : outcome == Outcome::kLapCap  ? "cap"
                                                        : "end";
      file.LapEvent(
          SessionEvent::Make(now, t, kind, -1, 255, rec.lap_time_s, ToString(outcome).c_str()));
    }
  }
  const record::SessionFileReport report = file.Close();
  for (auto& v : vehicles_) {
    v->out.result.session_file = report;
    if (report.saved) v->out.result.record.session_file = report.file.string();
  }
  if (first_.progress && !report.saved)
    log::Warn("session file " + report.file.string() + " NOT saved: " + report.error);
}

void SessionLoop::StopLinks() {
  if (!turns_) {
    vehicles_.front()->link->Stop();
    return;
  }
  // Every vehicle released and ended at once: one after the other, each
  // would wait for the others' processes to end, past its watchdog.
  std::vector<std::thread> stopping;
  for (auto& v : vehicles_) {
    if (!v->lost) v->link->SendSafe();
    stopping.emplace_back([link = v->link.get()] { link->Stop(); });
  }
  for (std::thread& thread : stopping) thread.join();
}

}  // namespace

SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted) {
  SessionLoop loop({&setup}, nullptr, nullptr, interrupted);
  loop.Run();
  return std::move(loop.vehicles().front()->out.result);
}

FleetResult RunSession(const FleetSetup& setup, const std::atomic<bool>& interrupted) {
  std::vector<const SessionSetup*> setups;
  for (const SessionSetup& s : setup.vehicles) setups.push_back(&s);
  FleetResult fleet;
  SessionLoop loop(setups, &setup.fleet, &fleet, interrupted);
  loop.Run();
  for (auto& v : loop.vehicles()) fleet.vehicles.push_back(std::move(v->out));
  return fleet;
}

}  // namespace haptel::mediator
