// The robot family's part of a session (family_session.hpp): the track and
// its lap timer, the switchable interfaces and the physics world their
// controls (or the scene) need, the automatic driver or a person.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <memory>
#include <vector>

#include "family_session.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/mediator/interface_set.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/mediator/notice_log.hpp"
#include "haptel/mediator/operator.hpp"
#include "haptel/mediator/predictive_display.hpp"
#include "haptel/mediator/robot_predictor.hpp"
#include "haptel/mediator/third_person_view.hpp"

namespace haptel::mediator {

namespace {

/// The predictive display's path ahead: how far, and a pose how often.
constexpr double kPathAhead_s = 1.0;
constexpr double kPathSpacing_s = 0.05;
/// The predictor's integration step (RobotPredictor's default).
constexpr double kPredictorStep_s = 0.005;

/// How long the end of a run waits for a physics step in progress.
constexpr double kPhysicsStopWait_s = 0.1;

/// The interfaces a run builds: the one it starts with, and — when the
/// operator may switch — every other one listed.
std::vector<bool> InterfacesToBuild(const SessionSetup& setup, bool can_switch) {
  std::vector<bool> build(setup.interfaces.size(), can_switch);
  build[static_cast<size_t>(setup.start_interface)] = true;
  return build;
}

/// The state's range scan (empty without range sensors; beams past the
/// scan's capacity are not kept).
RangeScan RangesOf(const msg::VehicleState& s) {
  RangeScan scan;
  scan.count = static_cast<int>(std::min<size_t>(s.ranges().size(), kMaxRangeBeams));
  scan.angle_min = s.range_angle_min();
  scan.angle_increment = s.range_angle_increment();
  scan.range_max = s.range_max();
  std::copy_n(s.ranges().begin(), scan.count, scan.ranges.begin());
  return scan;
}

/// What the predictor estimated of the drive, under the truth record's
/// names (its truths filled in when the run is scored).
void RecordEstimates(const RobotPredictor& predictor, RunRecord& rec) {
  const DriveEstimator& e = predictor.estimator();
  const auto known = [](double s) { return s >= 0.0 ? s : std::nan(""); };
  rec.estimated = {
      {"left_gain", e.left_gain(), std::nan(""), known(predictor.gains_known_s())},
      {"right_gain", e.right_gain(), std::nan(""), known(predictor.gains_known_s())},
      {"effective_track_width", e.track_width(), std::nan(""), known(predictor.width_known_s())},
  };
}

class RobotSession final : public FamilySession {
 public:
  RobotSession(const SessionSetup& setup, HapticSide& haptic, interfaces::InputBox& input,
               const std::atomic<bool>& interrupted, RunRecord& rec)
      : setup_(setup),
        track_(setup.track),
        lap_(track_),
        overlay_feed_(setup, track_),
        input_(&input),
        predictor_(setup.vehicle.drive, setup.vehicle.watchdog_timeout_s, kPredictorStep_s,
                   setup.predict_model),
        display_(setup.vehicle.camera, setup.vehicle.body.radius) {
    path_ahead_.reserve(static_cast<size_t>(kPathAhead_s / kPathSpacing_s) + 2);
    if (setup.keep_predictor_inputs) predictor_.KeepInputs();
    if (setup.localise) predictor_.Localise(track_);
    rec.track = setup.track.name;
    rec.predict = setup.predict;
    rec.predict_model = PredictionModelName(setup.predict_model);
    rec.gates_total = static_cast<int>(track_.gates().size());
    rec.interface = start_spec().name;
    if (setup.operator_kind == "auto") {
      if (haptic.sim() == nullptr) {
        throw ConfigError(setup.device.file.string() +
                          ": the automatic operator moves the simulated arms (driver 'sim'); "
                          "device '" +
                          setup.device.name + "' is driven by a person: use --operator person");
      }
      automatic_ =
          std::make_unique<AutomaticOperator>(track_, setup.run.op, setup.vehicle.drive,
                                              *haptic.sim(), setup.driver, setup.driver_experience);
      op_ = automatic_.get();
    } else {
      person_ = std::make_unique<PersonOperator>();
      op_ = person_.get();
    }

    // Physics, when an interface the run builds or the scene needs it — and
    // for an interface a person may switch to later (a cockpit while driving
    // by keys), not before it is first asked for: two proxy hands nobody
    // holds would otherwise run at 1 kHz all along.
    const std::vector<bool> build =
        InterfacesToBuild(setup, op_->can_switch() && !setup.single_interface);
    const bool defer_world = !start_spec().needs_physics() && !setup.scene;
    deferred_.assign(setup.interfaces.size(), false);
    for (size_t i = 0; i < setup.interfaces.size(); ++i) {
      if (!build[i]) continue;
      const interfaces::InterfaceSpec& spec = setup.interfaces[i];
      for (int s = 0; s < haptics::kSides; ++s) hands_[s] = hands_[s] || spec.hands()[s];
      // One set of controls for the cockpits: the one the run starts with, else the first listed.
      if (const auto* c = spec.config_as<CockpitConfig>();
          c != nullptr &&
          (cockpit_config_ == nullptr || i == static_cast<size_t>(setup.start_interface))) {
        cockpit_config_ = c;
      }
      gamepad_ = gamepad_ || spec.is_gamepad();
      deferred_[i] = defer_world && spec.needs_physics();
    }
    if (!defer_world) {
      const Scene* scene = setup.scene ? &*setup.scene : nullptr;
      physics_ = SessionPhysics::CreateIfNeeded(setup.physics, hands_, cockpit_config_, scene,
                                                &interrupted);
      if (interrupted.load()) return;  // the session abandons the set-up
    }

    // The interfaces (a deferred one's place stays empty until it is asked for).
    std::vector<std::unique_ptr<interfaces::MediatorInterface>> built;
    for (size_t i = 0; i < setup.interfaces.size(); ++i) {
      built.push_back(build[i] && !deferred_[i]
                          ? interfaces::MakeInterface(setup.interfaces[i], Parts())
                          : nullptr);
    }
    interfaces_ = std::make_unique<InterfaceSet>(std::move(built), setup.start_interface,
                                                 setup.run.switch_ramp_s);
    op_->Prepare(interfaces_->current());
    // The third-person view, drawn only where there is a view to show it.
    if (setup.third_person && setup.view != ViewKind::kNone) {
      third_person_ = std::make_unique<ThirdPersonView>(track_, setup.vehicle);
    }
  }

  void Start(HapticSide& haptic) override {
    if (physics_) physics_->world->Start(haptic.hal());
  }

  void AbandonSetup(SessionResult& result) override {
    if (!physics_) return;
    result.scene_bodies = static_cast<int>(physics_->scene.nodes.size());
    physics_->DetachTeardown();
  }

  void ConfigureView(SessionView::Parts& parts, view::ViewOptions&) const override {
    parts.physics = physics_.get();
    parts.cockpit = cockpit_config_;
    parts.hands = start_spec().hands();
    if (setup_.predict) parts.map = std::make_shared<const view::TrackMap>(TrackMapOf(track_));
    parts.third_person = third_person_.get();
  }
  bool UsesGamepad() const override { return gamepad_; }
  const SessionPhysics* physics() const override { return physics_.get(); }

  void Drain(VehicleLink& link, VehicleHealth& health, HapticSide& haptic, RunTrace& trace,
             int64_t t0) override {
    t0_ns_ = t0;  // the shown poses' clock, for scoring after the run
    for (const auto& e : link.channel<link::RobotMessages>().inbox().Drain()) {
      const msg::VehicleState& s = e.state;
      if (health.FromAnotherProcess(s))
        continue;  // a stranger under the name: the next check ends the run
      const double ts = NsToS(e.received_ns - t0);
      if (health.OnState(s, e.received_ns)) haptic.OnVehicleUp();
      const bool touching = s.bumper_left() || s.bumper_right();
      // A contact begun: the devices show it on the hands (a shake) at their next tick.
      if (touching && !touching_) haptic.hal().MarkContact();
      touching_ = touching;
      if (s.last_command_sent_ns() > 0) {
        predictor_.OnRoundTrip(
            NsToS(e.received_ns - s.last_command_sent_ns() - s.last_command_age_ns()));
      }
      bumpers_ = {s.bumper_left(), s.bumper_right()};
      const RangeScan ranges = RangesOf(s);
      if (s.pose_valid()) {
        predictor_.OnState({ts, s.x(), s.y(), s.heading(), s.speed(), s.yaw_rate(),
                            s.motor_left_level(), s.motor_right_level(), NsToS(s.stamp_ns()),
                            touching, ranges});
        // Where the robot is: its odometry, localised on the track when it
        // has ranges (the predictor's pose).
        const Pose2& at = predictor_.pose();
        reported_ = {ts, at.x, at.y, at.heading};
        // With prediction the operator sees the vehicle where it is now (Command).
        if (!setup_.predict) {
          const Pose2 seen = OnTrack(at);
          op_->Observe({ts, seen.x, seen.y, seen.heading, s.bumper_left(), s.bumper_right()});
        }
        lap_.Update(ts, Vec2(at.x, at.y));
        // The distance driven is the odometry's (the encoders count it).
        const double driven_m = odometry_ ? (Vec2(s.x(), s.y()) - *odometry_).norm() : 0.0;
        odometry_ = Vec2(s.x(), s.y());
        trace.Add(ts, at.x, at.y, 0.0, s.speed(), touching, driven_m);
      }
      lap_.UpdateContact(ts, touching);
      feedback_ = {s.bumper_left(), s.bumper_right(), s.speed(), ranges};
      if (feedback_.ranges.count != range_beams_said_) SayRanges(feedback_.ranges);
      third_person_pose_new_ = third_person_pose_new_ || s.pose_valid();
    }
    if (msg::CanLogStatus log; link.TakeCanLog(log)) OnCanLog(log);
    // The third-person view follows the newest pose, at most at its rate.
    if (third_person_ && third_person_pose_new_ && reported_) {
      const int64_t now = MonotonicNs();
      if (now >= next_third_person_ns_) {
        next_third_person_ns_ = now + static_cast<int64_t>(1e9 / ThirdPersonView::kRate_hz);
        third_person_pose_new_ = false;
        third_person_->Update(*reported_);
      }
    }
  }

  std::optional<LoopEnd> Command(double t, int64_t now, const interfaces::InputState& person,
                                 bool vehicle_up, bool engaged, HapticSide& haptic,
                                 VehicleLink& link) override {
    // A person's requests: another interface (F1–F6); a controller that went away.
    if (person.interface_requests != requests_seen_) {
      requests_seen_ = person.interface_requests;
      if (!op_->can_switch()) {
        if (setup_.progress) log::Info("the automatic operator does not switch interfaces");
      } else if (setup_.single_interface) {
        if (setup_.progress) log::Info("this run keeps its one interface (no switching)");
      } else if (BuildDeferred(person.interface_request)) {
        pending_switch_ = -1;  // a later request replaces one waiting for the world
        if (interfaces_->Request(person.interface_request, t) && setup_.progress) {
          log::Info("switching to interface '" + interfaces_->at(person.interface_request)->name() +
                    "'");
        }
      }
    }
    FinishDeferred(t, haptic);
    if (person.pad_disconnects != disconnects_seen_) {
      disconnects_seen_ = person.pad_disconnects;
      if (setup_.interfaces[static_cast<size_t>(interfaces_->current_index())].is_gamepad())
        return LoopEnd{Outcome::kAborted, "the game controller was disconnected"};
    }
    // The operator acts on the device; the interface reads the device.
    // With prediction the operator steers the vehicle as it will be when the
    // command given now reaches it: the commands on their way are known, so
    // this is the end of the ghost's first stretch of path, where a driver
    // watching the path ahead looks.
    if (setup_.predict && predictor_.ready()) {
      const PredictedPose ahead = predictor_.PoseAt(t + predictor_.one_way_delay_s());
      const Pose2 seen = OnTrack({ahead.x, ahead.y, ahead.heading});
      op_->Observe({t, seen.x, seen.y, seen.heading, bumpers_[0], bumpers_[1]});
    }
    // The operator drives once the interface engages (the automatic one
    // holds its hands where it prepared them until then, as a person takes
    // hold before driving).
    if (vehicle_up && !engaged && acted_) op_->Rest(interfaces_->current());
    if (vehicle_up && engaged) {
      acted_ = true;
      op_->Act(t, interfaces_->current());
      if (grasp_s_ == 0.0 && op_->grasped(t) && start_spec().needs_physics()) grasp_s_ = t;
    }
    motors_ = interfaces_->Update(t, feedback_, haptic.hal());
    if (const char* notice = notice_log_.Update(t, interfaces_->current().Notice()))
      log::Warn(notice);
    const auto command_period_ns = static_cast<int64_t>(
        1e9 /
        setup_.interfaces[static_cast<size_t>(interfaces_->current_index())].command_rate_hz());
    if (next_command_ns_ == 0) next_command_ns_ = now;
    const TreadCommand due = vehicle_up && engaged ? motors_ : TreadCommand{};
    const bool changed = due.left != last_sent_.left || due.right != last_sent_.right;
    if (CommandDue(next_command_ns_, now, command_period_ns, changed)) {
      link.Send(due);
      last_sent_ = due;
      predictor_.OnCommand(t, due.left, due.right);
    }
    command_period_ns_ = command_period_ns;
    // A person's hands move between ticks; the automatic operator's only at
    // a tick, so its commands keep to the tick.
    between_ticks_ = vehicle_up && engaged && op_ == person_.get();
    return std::nullopt;
  }

  bool CommandBetweenTicks(double t, int64_t now, HapticSide& haptic, VehicleLink& link) override {
    if (!between_ticks_ || interfaces_->switching()) return false;
    const std::optional<TreadCommand> command = interfaces_->current().CommandNow(t, haptic.hal());
    if (!command) return false;
    if (LevelsChange(last_sent_, *command, setup_.vehicle.drive.speed_levels)) {
      link.Send(*command);
      last_sent_ = motors_ = *command;
      predictor_.OnCommand(t, command->left, command->right);
      next_command_ns_ = now + command_period_ns_;  // the period counts from the last one sent
    }
    return true;
  }

  InterfaceRest Rest() const override {
    const interfaces::InterfaceSpec& spec =
        setup_.interfaces[static_cast<size_t>(interfaces_->current_index())];
    if (spec.manual()) return {};
    return RestOf(spec.hands(), interfaces_->current().HandTargetsFor({}), AtRest(motors_));
  }

  bool SwitchingInterface() const override { return interfaces_->switching(); }

  // --- A fleet's interface handover (interface_handover.hpp). ---
  void RenderForces(double t, haptics::Hal& hal) override {
    // Its command goes nowhere: the vehicle is held safe meanwhile.
    interfaces_->current().Update(t, feedback_, hal);
  }
  void PauseForces(haptics::Hal&) override {
    // Stopped, not torn down: its bodies and hands wait for the return.
    // The stop takes the coupling out of the HAL (PhysicsWorld::RequestStop),
    // so no other vehicle's world ever shares the set-point slot with it.
    if (physics_ && physics_->world->running()) physics_->world->Stop();
  }
  void ResumeForces(haptics::Hal& hal, const interfaces::InputState& now) override {
    if (physics_ && !physics_->world->running()) physics_->world->Start(hal);
    // Keys pressed and interfaces asked for while another vehicle was
    // driven were that one's: none of them reaches this vehicle.
    interfaces_->current().Rebase(now);
    requests_seen_ = now.interface_requests;
    disconnects_seen_ = now.pad_disconnects;
    motors_ = {};
  }

  std::optional<LoopEnd> LapEnd() const override {
    if (lap_.completed()) return LoopEnd{Outcome::kCompleted, "lap completed"};
    return std::nullopt;
  }
  const std::filesystem::path& world_file() const override { return setup_.track.file; }
  double lap_cap_s() const override { return setup_.track.lap_cap_s; }
  std::optional<double> lap_start_s() const override {
    return lap_.started() ? std::optional<double>(lap_.start_t_s()) : std::nullopt;
  }

  view::Overlay Overlay(double t, bool vehicle_up, bool touching) override {
    return overlay_feed_.Make(t, lap_, *interfaces_, feedback_, motors_, vehicle_up, touching);
  }

  /// Where the operator sees the robot at `pose` (the localiser's map):
  /// against the walls and posts around it, on the track it knows (the
  /// file's; TrackLocaliser::OnFileMap). A person watching the camera
  /// steers by the corridor in the picture, not by the map's frame, which
  /// moves as a learnt map settles (harsh, 0 ms, seeds 21-40: steering on
  /// the learnt map's frame drove laps 0.43 s [0.25, 0.61] longer than the
  /// file's map).
  Pose2 OnTrack(const Pose2& pose) const {
    const TrackLocaliser* map = predictor_.localiser();
    return map != nullptr ? map->OnFileMap(pose) : pose;
  }

  /// With prediction on: the ghost now and its path ahead with the command
  /// being given, seen from the newest state's pose (the picture's; see
  /// predictive_display.hpp). Nothing is shown before the first pose.
  std::optional<view::Prediction> Prediction(double t) override {
    if (!setup_.predict) return std::nullopt;
    view::Prediction shown;
    if (!predictor_.ready() || !reported_) return shown;  // shown == false: nothing drawn yet
    predictor_.PathAhead(t, kPathAhead_s, motors_.left, motors_.right, path_ahead_, kPathSpacing_s);
    display_.Make(*reported_, path_ahead_, predictor_.one_way_delay_s(), shown);
    return shown;
  }

  /// Progress lines every 2 s on stderr: the lap, the vehicle and the link,
  /// and a cockpit's controls.
  void LogProgress(double t, const VehicleLink& link, double distance_m) const override {
    const interfaces::MediatorInterface& interface = interfaces_->current();
    char line[260];
    std::snprintf(line, sizeof line,
                  "%6.1f s  %s  lap %5.1f s  gates %d/%d  obstacles %d  speed %.2f m/s  distance "
                  "%.2f m  rtt p50 %.2f ms  "
                  "video %.1f fps",
                  t, interface.name().c_str(), lap_.lap_time_s(), lap_.next_gate(),
                  lap_.gates_total(), lap_.obstacles_touched(), feedback_.speed, distance_m,
                  link.Rtt().Percentile(0.5) * 1e-3, link.video().Stats().fps);
    log::Info(line);
    if (const std::string controls = interface.ProgressLine(motors_); !controls.empty())
      log::Info(controls);
  }

  const char* MadeSafe() const override { return "forces zeroed, vehicle stopped"; }

  void RequestStop() override {
    if (physics_) physics_->world->RequestStop();
  }

  void Finish(SessionResult& result, bool progress) override {
    if (physics_) {
      // A step of thousands of overlapping bodies takes seconds: give it a
      // moment to give up (it does between contacts), then leave it, and the
      // world's teardown, to a thread of their own; the run is recorded now.
      if (!physics_->world->Stop(kPhysicsStopWait_s) && progress) {
        log::Info("physics step still running at the end of the run; left to finish on its own");
      }
      physics_->DetachTeardown();
      const LoopStats p = physics_->world->Stats();
      const physics::PhysicsCounters counters = physics_->world->Counters();
      result.physics_rate_hz = p.rate_hz;
      result.physics_period_p99_us = p.period_p99_us;
      result.physics_step_max_us = counters.max_step_us;
      result.physics_hand_resets = counters.hand_resets;
      result.scene_bodies = static_cast<int>(physics_->scene.nodes.size());
    }
    result.grasp_s = grasp_s_;
    if (start_spec().needs_physics() && result.grasp_s == 0.0) result.grasp_s = -1.0;
    if (automatic_) result.operator_slips = automatic_->driver().slips();
    RunRecord& rec = result.record;
    rec.lap_time_s = lap_.lap_time_s();
    rec.gates_passed = lap_.gates_passed();
    rec.gates_missed = lap_.gates_missed();
    rec.obstacles_touched = lap_.obstacles_touched();
    rec.splits = lap_.splits();
    rec.switches = interfaces_->switches();
    RecordPredictionErrors(predictor_.errors_m(), rec);
    result.shown = predictor_.shown();
    result.located = predictor_.located();
    result.odometry = predictor_.odometry();
    rec.localised = predictor_.localiser() != nullptr && predictor_.localiser()->started();
    if (rec.localised) {
      rec.localiser_scans_refused = predictor_.localiser()->scans_refused();
      for (const MapFeature& f : predictor_.localiser()->Map())
        result.learnt_map.emplace_back(f.file, f.learnt);
    }
    result.predictor_inputs = predictor_.inputs();
    result.started_ns = t0_ns_;
    result.shown_height = false;
    RecordEstimates(predictor_, rec);
    result.can_log = can_log_;
  }

 private:
  /// Says what the vehicle's range sensors give shared control to look with,
  /// when it first comes and whenever it changes: a laser that came late or
  /// a scan that stopped (a ROS 2 robot's goes when its scans stop).
  void SayRanges(const RangeScan& scan) {
    range_beams_said_ = scan.count;
    if (!setup_.progress) return;
    if (scan.count == 0) {
      log::Info("range sensors: none now (the vehicle's scan is empty)");
      return;
    }
    constexpr double kDeg = 180.0 / 3.14159265358979323846;
    char line[160];
    std::snprintf(line, sizeof line,
                  "range sensors: %d beams from %+.0f deg to %+.0f deg, up to %.2f m", scan.count,
                  scan.Angle(0) * kDeg, scan.Angle(scan.count - 1) * kDeg, scan.range_max);
    log::Info(line);
  }

  const interfaces::InterfaceSpec& start_spec() const {
    return setup_.interfaces.at(static_cast<size_t>(setup_.start_interface));
  }

  /// The vehicle's CAN bus log (its own topic, a CAN robot's): kept as
  /// reported; its end said once, as the status first carries it (the
  /// robot drives on).
  void OnCanLog(const msg::CanLogStatus& s) {
    if (s.path().empty()) return;
    can_log_.path = s.path();
    can_log_.frames = s.frames();
    can_log_.frames_lost = s.frames_lost();
    if (can_log_.error.empty() && !s.error().empty()) {
      can_log_.error = s.error();
      log::Error("vehicle '" + setup_.vehicle.name +
                 "': its CAN bus log is not recorded whole: " + can_log_.error);
    }
  }

  /// What the interfaces are built on.
  interfaces::InterfaceParts Parts() const {
    interfaces::InterfaceParts parts;
    parts.controls = physics_ && physics_->port ? physics_->port.get() : nullptr;
    parts.input = input_;
    parts.speed_levels = setup_.vehicle.drive.speed_levels;
    parts.vehicle = {.max_speed = setup_.vehicle.drive.max_speed,
                     .track_width = setup_.vehicle.drive.track_width,
                     .body_radius = setup_.vehicle.body.radius};
    return parts;
  }

  /// Before a switch to `index`: true when it can be switched to now. When
  /// its interface waits for the physics world, starts building the world on
  /// a thread of its own and returns false; FinishDeferred switches once it
  /// is built. A cockpit's world takes 0.1-0.7 s to build, and the session
  /// loop must keep commanding the vehicle meanwhile (its watchdog would stop
  /// it): the current interface drives on until then.
  bool BuildDeferred(int index) {
    if (index < 0 || index >= static_cast<int>(deferred_.size()) ||
        !deferred_[static_cast<size_t>(index)]) {
      return true;
    }
    pending_switch_ = index;
    if (!building_.valid()) {
      build_start_ns_ = MonotonicNs();
      // Reads only what the constructor settled (the physics configuration,
      // the hands, the cockpit's controls).
      building_ = std::async(std::launch::async, [this] {
        return SessionPhysics::CreateIfNeeded(setup_.physics, hands_, cockpit_config_, nullptr);
      });
      if (setup_.progress) {
        log::Info("building the physics world for '" +
                  setup_.interfaces[static_cast<size_t>(index)].name +
                  "'; the current interface drives on meanwhile");
      }
    }
    return false;
  }

  /// Once the world BuildDeferred started is built: starts it on the HAL,
  /// gives every interface that waited for it its parts, and switches to the
  /// one last asked for (if the person has not asked for another since).
  void FinishDeferred(double t, HapticSide& haptic) {
    if (!building_.valid() ||
        building_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
      return;
    const int index = pending_switch_;
    pending_switch_ = -1;
    const std::string name =
        index >= 0 ? setup_.interfaces[static_cast<size_t>(index)].name : "a later interface";
    try {
      physics_ = building_.get();
      if (physics_) physics_->world->Start(haptic.hal());
      for (size_t i = 0; i < deferred_.size(); ++i) {
        if (!deferred_[i]) continue;
        interfaces_->Provide(static_cast<int>(i),
                             interfaces::MakeInterface(setup_.interfaces[i], Parts()));
        deferred_[i] = false;
      }
    } catch (const std::exception& e) {
      log::Error("interface '" + name + "' cannot be built: " + e.what());
      std::fill(deferred_.begin(), deferred_.end(), false);
      return;
    }
    if (setup_.progress) {
      log::Info("physics world built for '" + name + "' in " +
                std::to_string(static_cast<int>(NsToS(MonotonicNs() - build_start_ns_) * 1e3)) +
                " ms");
    }
    if (index >= 0 && interfaces_->Request(index, t) && setup_.progress) {
      log::Info("switching to interface '" + interfaces_->at(index)->name() + "'");
    }
  }

  const SessionSetup& setup_;
  const Track track_;
  LapTimer lap_;
  OverlayFeed overlay_feed_;
  NoticeLog notice_log_;
  std::unique_ptr<AutomaticOperator> automatic_;
  std::unique_ptr<PersonOperator> person_;
  Operator* op_ = nullptr;
  interfaces::InputBox* input_ = nullptr;
  std::array<bool, haptics::kSides> hands_{
      false, false};  ///< proxy hands a world gives the interfaces built
  const CockpitConfig* cockpit_config_ = nullptr;
  /// Interfaces waiting for the physics world (built when first asked for).
  std::vector<bool> deferred_;
  bool gamepad_ = false;
  std::unique_ptr<SessionPhysics> physics_;
  std::unique_ptr<InterfaceSet> interfaces_;
  interfaces::VehicleFeedback feedback_;
  /// The beams the range scan had when last said (SayRanges).
  int range_beams_said_ = 0;
  TreadCommand motors_;
  TreadCommand last_sent_;  ///< the command last sent (a change goes out at once)
  uint32_t requests_seen_ = 0;
  uint32_t disconnects_seen_ = 0;
  int64_t next_command_ns_ = 0;
  int64_t command_period_ns_ = 0;  ///< the current interface's, as of the last tick
  /// The last tick had the person engaged with the vehicle up: commands may
  /// go between ticks (CommandBetweenTicks).
  bool between_ticks_ = false;
  double grasp_s_ = 0.0;
  bool acted_ = false;  ///< the operator has driven (engaged) since the start
  RobotPredictor predictor_;
  int64_t t0_ns_ = 0;  ///< the session's start (MonotonicNs), as Drain is given it
  PredictiveDisplay display_;
  std::optional<PredictedPose> reported_;  ///< the newest state's pose, when one had a pose
  std::optional<Vec2> odometry_;           ///< the newest state's odometry position
  /// The third-person view (setup.third_person with a view; null otherwise),
  /// whether a pose came since it last drew, and when it may draw next.
  std::unique_ptr<ThirdPersonView> third_person_;
  bool third_person_pose_new_ = false;
  int64_t next_third_person_ns_ = 0;
  std::vector<PredictedPose> path_ahead_;
  std::array<bool, 2> bumpers_{false, false};  ///< the newest state's, left and right
  bool touching_ = false;                      ///< either bumper, in the newest state
  CanLogReport can_log_;
  /// The deferred physics world while it is built (BuildDeferred); last, so
  /// that it is waited for before the members its thread reads go.
  std::future<std::unique_ptr<SessionPhysics>> building_;
  int64_t build_start_ns_ = 0;
  int pending_switch_ = -1;  ///< the interface to switch to once it is built (-1: none)
};

}  // namespace

std::unique_ptr<FamilySession> MakeRobotSession(const SessionSetup& setup, HapticSide& haptic,
                                                interfaces::InputBox& input,
                                                const std::atomic<bool>& interrupted,
                                                RunRecord& rec) {
  return std::make_unique<RobotSession>(setup, haptic, input, interrupted, rec);
}

}  // namespace haptel::mediator
