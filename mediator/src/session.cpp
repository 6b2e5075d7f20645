#include "haptel/mediator/session.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/mediator/blimp_session.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/mediator/operator.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "session_loop.hpp"
#include "haptel/view/sdl_input.hpp"

namespace haptel::mediator {

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
      return 2;
    default:
      return 1;
  }
}

namespace {

/// How long the end of a run waits for a physics step in progress.
constexpr double kPhysicsStopWait_s = 0.1;

/// The interfaces a run builds: the one it starts with, and — when the
/// operator may switch — every other one listed.
std::vector<bool> InterfacesToBuild(const SessionSetup& setup, bool can_switch) {
  std::vector<bool> build(setup.interfaces.size(), can_switch);
  build[static_cast<size_t>(setup.start_interface)] = true;
  return build;
}

/// Progress lines every 2 s on stderr; then each loop that fell short of its
/// rate over the interval, and the counters that are not zero.
void LogProgress(double t, const LapTimer& lap, const VehicleLink& link, double speed,
                 double distance_m, const interfaces::MediatorInterface& interface,
                 const interfaces::MotorCommand& motors,
                 const std::vector<std::string>& short_loops, const std::string& counters) {
  const VideoStats v = link.video().Stats();
  char line[260];
  std::snprintf(line, sizeof line,
                "%6.1f s  %s  lap %5.1f s  gates %d/%d  obstacles %d  speed %.2f m/s  distance "
                "%.2f m  rtt p50 %.2f ms  "
                "video %.1f fps",
                t, interface.name().c_str(), lap.lap_time_s(), lap.next_gate(), lap.gates_total(),
                lap.obstacles_touched(), speed, distance_m,
                link.inbox().Rtt().Percentile(0.5) * 1e-3, v.fps);
  log::Info(line);
  if (const auto* cockpit = dynamic_cast<const interfaces::CockpitInterface*>(&interface)) {
    const interfaces::CockpitControls& c = cockpit->controls();
    const interfaces::HudState& h = cockpit->hud();
    char hud[80] = "";
    if (cockpit->logic().config().hud) {
      std::snprintf(hud, sizeof hud, "  HUD %.2f m/s%s%s%s", h.speed, h.turn_left ? " <" : "",
                    h.turn_right ? " >" : "", h.throttle_locked ? " locked" : "");
    }
    std::snprintf(line, sizeof line,
                  "         wheel %+.2f rad%s  throttle %+.3f m%s  motors %+.2f %+.2f%s",
                  c.wheel_angle, c.wheel_held ? " (held)" : "", c.throttle,
                  c.throttle_held ? " (held)" : "", motors.left, motors.right, hud);
    log::Info(line);
  }
  for (const std::string& loop : short_loops) log::Warn(loop);
  if (!counters.empty()) log::Info("         counters: " + counters);
}

}  // namespace

SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted) {
  if (setup.course) return RunBlimpSession(setup, interrupted);
  const RunConfig& run = setup.run;
  const Track track(setup.track);
  SessionResult result;
  RunRecord& rec = result.record;
  rec.started_wall_ns = WallNs();
  rec.config_name = run.name;
  rec.track = setup.track.name;
  rec.vehicle = setup.vehicle.name;
  rec.vehicle_kind = setup.vehicle.kind;
  rec.gates_total = static_cast<int>(track.gates().size());
  rec.operator_kind = setup.operator_kind;
  rec.device = setup.device.name;
  const InterfaceSpec& start_spec = setup.interfaces.at(static_cast<size_t>(setup.start_interface));

  // --- The haptic side first: the hands are held before anything moves. ---
  HapticSide haptic(setup.device, setup.calibration, setup.gravity, run.op, setup.trace);
  std::unique_ptr<Operator> op;
  if (setup.operator_kind == "auto") {
    if (haptic.sim() == nullptr) {
      throw ConfigError(setup.device.file.string() +
                        ": the automatic operator moves the simulated arms (driver 'sim'); "
                        "device '" +
                        setup.device.name + "' is driven by a person: use --operator person");
    }
    op = std::make_unique<AutomaticOperator>(track, run.op, setup.vehicle.drive, *haptic.sim(), setup.driver,
                                             setup.driver_experience);
  } else {
    op = std::make_unique<PersonOperator>();
  }

  // --- Physics, when an interface the run builds or the scene needs it. ---
  const std::vector<bool> build = InterfacesToBuild(setup, op->can_switch());
  std::array<bool, haptics::kSides> hands{false, false};
  const CockpitConfig* cockpit_config = nullptr;
  for (size_t i = 0; i < setup.interfaces.size(); ++i) {
    if (!build[i]) continue;
    const InterfaceSpec& spec = setup.interfaces[i];
    for (int s = 0; s < haptics::kSides; ++s) hands[s] = hands[s] || spec.hands()[s];
    // One set of controls for the cockpits: the one the run starts with, else the first listed.
    if (const auto* c = std::get_if<CockpitConfig>(&spec.config);
        c != nullptr &&
        (cockpit_config == nullptr || i == static_cast<size_t>(setup.start_interface))) {
      cockpit_config = c;
    }
  }
  const Scene* scene = setup.scene ? &*setup.scene : nullptr;
  std::unique_ptr<SessionPhysics> physics_side =
      SessionPhysics::CreateIfNeeded(setup.physics, hands, cockpit_config, scene, &interrupted);
  if (interrupted.load()) {
    // During the set-up (thousands of scene bodies take a while): nothing has
    // started yet, nothing is spawned; the run ends here, recorded.
    result.outcome = Outcome::kInterrupted;
    result.message = "interrupted by the operator during the set-up";
    rec.interface = start_spec.name;
    rec.outcome = ToString(result.outcome);
    if (physics_side) {
      result.scene_bodies = static_cast<int>(physics_side->scene.nodes.size());
      physics_side->DetachTeardown();
    }
    return result;
  }

  // --- The interfaces. ---
  interfaces::InputBox input;
  InterfaceParts parts;
  parts.controls = physics_side && physics_side->port ? physics_side->port.get() : nullptr;
  parts.input = &input;
  parts.speed_levels = setup.vehicle.drive.speed_levels;
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> built;
  for (size_t i = 0; i < setup.interfaces.size(); ++i) {
    built.push_back(build[i] ? MakeInterface(setup.interfaces[i], parts) : nullptr);
  }
  InterfaceSet interfaces(std::move(built), setup.start_interface, run.switch_ramp_s);
  op->Prepare(interfaces.current());
  // A person's controller without a view: a thread of its own polls it.
  std::unique_ptr<view::InputPump> pump;
  bool any_gamepad = false;
  for (size_t i = 0; i < setup.interfaces.size(); ++i)
    any_gamepad = any_gamepad || (build[i] && setup.interfaces[i].is_gamepad());
  if (any_gamepad && setup.view == ViewKind::kNone) pump = std::make_unique<view::InputPump>(input);

  haptic.Start(setup.progress);
  if (physics_side) physics_side->world->Start(haptic.hal());

  // --- The vehicle. ---
  VehicleLinkOptions link_options;
  link_options.vehicle = setup.vehicle;
  link_options.link = run.link;
  link_options.track_file = setup.track.file;
  link_options.program = setup.vehicle_program;
  link_options.decode_video = run.video_decode && DecodesVideo(setup.view);
  VehicleLink vehicle(link_options);
  rec.vehicle_pid = vehicle.pid();
  if (setup.progress && setup.attach) {
    log::Info("attached to vehicle '" + setup.vehicle.name + "' on domain " + std::to_string(run.link.domain_id) +
              " (session " + std::to_string(vehicle.session()) + "): spawning none");
  }
  if (setup.progress && vehicle.pid() != 0) {
    log::Info("vehicle '" + setup.vehicle.name + "' started, pid " + std::to_string(vehicle.pid()));
  }

  // --- The view, when something shows it: a window, or offscreen for the MP4. ---
  std::unique_ptr<SessionView> view_part;
  if (setup.view != ViewKind::kNone) {
    const view::ViewOptions options = ViewOptionsFor(setup);
    SessionView::Parts view_parts;
    view_parts.hal = &haptic.hal();
    view_parts.physics = physics_side.get();
    view_parts.physics_config = &setup.physics;
    view_parts.cockpit = cockpit_config;
    view_parts.video = &vehicle.video();
    view_parts.hands = start_spec.hands();
    view_part = std::make_unique<SessionView>(options, view_parts, input);
  }
  OverlayFeed overlay_feed(setup, track);

  LapTimer lap(track);
  const int64_t t0 = MonotonicNs();
  LoopWatch watch(haptic, physics_side.get(), vehicle, view_part.get(), t0);
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  int64_t next_command_ns = t0;
  int64_t next_progress_ns = t0 + SToNs(2.0);
  int64_t next_live_ns = t0;
  int64_t next_tick = t0;
  VehicleHealth health(setup.vehicle.name, run.link.domain_id, vehicle.session(), run.vehicle_timeout_s);
  interfaces::VehicleFeedback feedback;
  interfaces::MotorCommand motors;
  uint32_t requests_seen = 0;
  uint32_t disconnects_seen = 0;
  RunTrace trace(rec);
  rec.path.reserve(8192);
  const auto finish = [&](LoopEnd end) { Finish(result, std::move(end), "forces zeroed, vehicle stopped"); };

  for (;;) {
    SleepUntilNs(next_tick);
    next_tick += period_ns;
    const int64_t now = MonotonicNs();
    const double t = NsToS(now - t0);

    if (auto end = CheckOperatorSide(interrupted, haptic, setup.device.name)) {
      finish(std::move(*end));
      break;
    }
    const interfaces::InputState person = input.Load();
    if (person.quit) {
      finish({Outcome::kAborted, "the view was closed"});
      break;
    }
    if (auto end = health.CheckProcess(vehicle, now)) {
      finish(std::move(*end));
      break;
    }
    for (const auto& e : vehicle.inbox().Drain()) {
      const msg::VehicleState& s = e.state;
      const double ts = NsToS(e.received_ns - t0);
      if (health.OnState(s, e.received_ns)) haptic.OnVehicleUp();
      const bool touching = s.bumper_left() || s.bumper_right();
      if (s.pose_valid()) {
        op->Observe({ts, s.x(), s.y(), s.heading(), s.bumper_left(), s.bumper_right()});
        lap.Update(ts, Vec2(s.x(), s.y()));
        trace.Add(ts, s.x(), s.y(), 0.0, s.speed(), touching);
      }
      lap.UpdateContact(ts, touching);
      feedback = {s.bumper_left(), s.bumper_right(), s.speed()};
    }
    if (auto end = health.CheckStates(vehicle, now, t)) {
      finish(std::move(*end));
      break;
    }
    const bool vehicle_up = health.up();

    // A person's requests: another interface (F1–F6); a controller that went away.
    if (person.interface_requests != requests_seen) {
      requests_seen = person.interface_requests;
      if (!op->can_switch()) {
        if (setup.progress) log::Info("the automatic operator does not switch interfaces");
      } else if (interfaces.Request(person.interface_request, t) && setup.progress) {
        log::Info("switching to interface '" + interfaces.at(person.interface_request)->name() +
                  "'");
      }
    }
    if (person.pad_disconnects != disconnects_seen) {
      disconnects_seen = person.pad_disconnects;
      if (interfaces.current().name() == "gamepad") {
        finish({Outcome::kAborted, "the game controller was disconnected"});
        break;
      }
    }

    // The operator acts on the device; the interface reads the device.
    if (vehicle_up) {
      op->Act(t, interfaces.current());
      if (result.grasp_s == 0.0 && op->grasped(t) && start_spec.is_cockpit()) result.grasp_s = t;
    }
    motors = interfaces.Update(t, feedback, haptic.hal());
    const auto command_period_ns = static_cast<int64_t>(
        1e9 / setup.interfaces[static_cast<size_t>(interfaces.current_index())].command_rate_hz());
    if (CommandDue(next_command_ns, now, command_period_ns)) {
      vehicle.Send(vehicle_up ? motors.left : 0.0, vehicle_up ? motors.right : 0.0);
    }

    if (lap.completed()) {
      finish({Outcome::kCompleted, "lap completed"});
      break;
    }
    if (auto end = CheckLimits(t, setup.time_limit_s, setup.track.lap_cap_s)) {
      finish(std::move(*end));
      break;
    }
    if (view_part || setup.on_live) {
      // Made every tick: the overlay notices contacts by their edges.
      const view::Overlay overlay = overlay_feed.Make(t, lap, interfaces, feedback, motors, vehicle_up, trace.touching());
      if (view_part) view_part->Publish(overlay);
      if (setup.on_live && now >= next_live_ns) {
        next_live_ns = now + SToNs(0.5);
        setup.on_live(overlay);
      }
    }
    if (now >= next_progress_ns) {
      next_progress_ns += SToNs(2.0);
      const std::vector<std::string> short_loops = watch.EndInterval(now);
      if (setup.progress) {
        LogProgress(t, lap, vehicle, feedback.speed, rec.distance_m, interfaces.current(), motors,
                    short_loops, NonZeroCounters(watch.Counters()));
      }
    }
  }
  for (const std::string& loop : watch.EndInterval(MonotonicNs())) {
    if (setup.progress) log::Warn(loop);
  }

  // Make safe: forces to zero, motors stopped, vehicle process ended. The
  // physics world's forces leave the HAL at once too, whatever its step is doing.
  haptic.hal().ZeroForces();
  if (physics_side) physics_side->world->RequestStop();
  vehicle.Send(0.0, 0.0);
  if (view_part) StopAndRecord(*view_part, result);
  if (physics_side) {
    // A step of thousands of overlapping bodies takes seconds: give it a
    // moment to give up (it does between contacts), then leave it, and the
    // world's teardown, to a thread of their own; the run is recorded now.
    if (!physics_side->world->Stop(kPhysicsStopWait_s) && setup.progress) {
      log::Info("physics step still running at the end of the run; left to finish on its own");
    }
    physics_side->DetachTeardown();
    const LoopStats p = physics_side->world->Stats();
    const physics::PhysicsCounters counters = physics_side->world->Counters();
    result.physics_rate_hz = p.rate_hz;
    result.physics_period_p99_us = p.period_p99_us;
    result.physics_step_max_us = counters.max_step_us;
    result.physics_hand_resets = counters.hand_resets;
    result.scene_bodies = static_cast<int>(physics_side->scene.nodes.size());
  }
  if (start_spec.is_cockpit() && result.grasp_s == 0.0) result.grasp_s = -1.0;
  if (const auto* automatic = dynamic_cast<const AutomaticOperator*>(op.get())) {
    result.operator_slips = automatic->driver().slips();
  }
  haptic.Stop();
  vehicle.Stop();

  RecordLinkFigures(haptic, vehicle, result);
  rec.interface = start_spec.name;
  rec.lap_time_s = lap.lap_time_s();
  rec.gates_passed = lap.gates_passed();
  rec.gates_missed = lap.gates_missed();
  rec.obstacles_touched = lap.obstacles_touched();
  rec.splits = lap.splits();
  rec.switches = interfaces.switches();
  watch.Finish(rec);
  return result;
}

}  // namespace haptel::mediator
