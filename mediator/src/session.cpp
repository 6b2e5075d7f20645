#include "haptel/mediator/session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "family_session.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/link.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/view/sdl_input.hpp"
#include "simulated_time.hpp"

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

}  // namespace

SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted) {
  const int64_t wall_start_ns = RealMonotonicNs();
  const double cpu_start_s = ThreadCpuSeconds();
  // In simulated time the clock comes first: every stamp the set-up takes is
  // on it. Destroyed last, back to the real clock.
  std::unique_ptr<SimulatedTime> simulated;
  if (setup.simulated_time) simulated = std::make_unique<SimulatedTime>(setup);
  const RunConfig& run = setup.run;
  SessionResult result;
  RunRecord& rec = result.record;
  rec.started_wall_ns = WallNs();
  rec.config_name = run.name;
  rec.vehicle = setup.vehicle.name;
  rec.vehicle_kind = setup.vehicle.kind;
  rec.link_fault = setup.run.link.fault.enabled ? LinkFaultText(setup.run.link.fault) : "";
  rec.operator_kind = setup.operator_kind;
  rec.device = setup.device.name;

  // --- The haptic side first, then the family's part (its world, its
  // interfaces, its operator): the hands are held before anything moves. ---
  HapticSide haptic(setup.device, setup.calibration, setup.gravity, run.op, setup.trace);
  interfaces::InputBox input;
  std::unique_ptr<FamilySession> family;
  switch (setup.vehicle.family()) {
    case VehicleFamily::kRobot:
      family = MakeRobotSession(setup, haptic, input, interrupted, rec);
      break;
    case VehicleFamily::kBlimp:
      family = MakeBlimpSession(setup, haptic, input, rec);
      break;
  }
  if (interrupted.load()) {
    // During the set-up (thousands of scene bodies take a while): nothing has
    // started yet, nothing is spawned; the run ends here, recorded.
    result.outcome = Outcome::kInterrupted;
    result.message = "interrupted by the operator during the set-up";
    rec.outcome = ToString(result.outcome);
    family->AbandonSetup(result);
    return result;
  }
  if (!simulated) {
    // In simulated time these are stepped by the session's own thread (AdvanceTo).
    haptic.Start(setup.progress);
    family->Start(haptic);
  }

  // --- The vehicle. ---
  VehicleLinkOptions link_options;
  link_options.vehicle = setup.vehicle;
  link_options.link = run.link;
  link_options.track_file = family->world_file();
  link_options.program = setup.vehicle_program;
  link_options.decode_video = run.video_decode && DecodesVideo(setup.view);
  if (simulated) {
    link_options.program.clear();
    link_options.in_process_robot = [&simulated](const msg::TreadCommand& command) {
      simulated->OnCommand(command);
    };
  }
  VehicleLink vehicle(link_options);
  rec.vehicle_pid = vehicle.pid();
  if (setup.progress && setup.attach) {
    log::Info("attached to vehicle '" + setup.vehicle.name + "' on domain " +
              std::to_string(run.link.domain_id) + " (session " +
              std::to_string(vehicle.session()) + "): spawning none");
  }
  if (setup.progress && simulated) {
    log::Info("vehicle '" + setup.vehicle.name + "' (" + setup.vehicle.kind +
              ") stepped in this process, on the simulated clock");
  }
  if (setup.progress && vehicle.pid() != 0) {
    log::Info("vehicle '" + setup.vehicle.name + "' (" + setup.vehicle.kind + ") started, pid " +
              std::to_string(vehicle.pid()));
  }

  // --- The view, when something shows it: a window, or offscreen for the MP4. ---
  std::unique_ptr<SessionView> view_part;
  if (setup.view != ViewKind::kNone) {
    view::ViewOptions options = ViewOptionsFor(setup);
    SessionView::Parts view_parts;
    view_parts.hal = &haptic.hal();
    view_parts.physics_config = &setup.physics;  // the hands' size, with or without a world
    view_parts.video = &vehicle.video();
    family->ConfigureView(view_parts, options);
    view_part = std::make_unique<SessionView>(options, view_parts, input);
  }
  // A person's controller without a view: a thread of its own polls it.
  std::unique_ptr<view::InputPump> pump;
  if (family->UsesGamepad() && !view_part) pump = std::make_unique<view::InputPump>(input);

  const int64_t t0 = MonotonicNs();
  LoopWatch watch(haptic, family->physics(), vehicle, view_part.get(), t0);
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  int64_t next_progress_ns = t0 + SToNs(2.0);
  int64_t next_live_ns = t0;
  uint64_t pictures_seen = 0;
  int64_t next_tick = t0;
  VehicleHealth health(setup.vehicle.name, run.link.domain_id, vehicle.session(),
                       vehicle.command_writer(), run.vehicle_timeout_s,
                       VehicleHealth::kStartupTimeout_s, vehicle.pid());
  RunTrace trace(rec);
  rec.path.reserve(16384);
  const auto finish = [&](LoopEnd end) { Finish(result, std::move(end), family->MadeSafe()); };

  for (;;) {
    if (simulated) {
      simulated->AdvanceTo(next_tick, haptic, family->physics(), vehicle);
    } else {
      SleepUntilNs(next_tick);
    }
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
    family->Drain(vehicle, health, haptic, trace, t0);
    if (auto end = health.CheckStates(vehicle, now, t)) {
      finish(std::move(*end));
      break;
    }
    const bool vehicle_up = health.up();
    if (auto end = family->Drive(t, now, person, vehicle_up, haptic, vehicle)) {
      finish(std::move(*end));
      break;
    }
    if (family->physics() != watch.physics()) {
      // A world built for an interface just asked for: watched and drawn from now on.
      watch.AddPhysics(family->physics(), now);
      if (view_part) view_part->SetPhysics(family->physics());
    }
    // Twice a second, whoever watches the run live (a study's console).
    const bool live_due = (setup.on_live || setup.on_picture) && now >= next_live_ns;
    if (live_due) next_live_ns = now + SToNs(0.5);
    if (view_part || setup.on_live) {
      // Made every tick: the overlay notices contacts by their edges.
      const view::Overlay overlay = family->Overlay(t, vehicle_up, trace.touching());
      if (view_part) {
        view_part->Publish(overlay);
        if (const std::optional<view::Gaze> gaze = family->Gaze()) view_part->Publish(*gaze);
        if (const std::optional<view::Prediction> prediction = family->Prediction(t))
          view_part->Publish(*prediction);
      }
      if (setup.on_live && live_due) setup.on_live(overlay);
    }
    if (setup.on_picture && live_due) {
      const uint64_t frames = vehicle.video().Stats().frames;
      if (frames != pictures_seen) {
        pictures_seen = frames;
        setup.on_picture(vehicle.video().LatestPicture(), frames);
      }
    }
    if (auto end = family->LapEnd()) {
      finish(std::move(*end));
      break;
    }
    if (auto end = CheckLimits(t, family->lap_start_s(), setup.time_limit_s, setup.lap_limit_s,
                               family->lap_cap_s())) {
      finish(std::move(*end));
      break;
    }
    if (now >= next_progress_ns) {
      next_progress_ns += SToNs(2.0);
      // In simulated time every loop keeps its rate by construction (no thread measures it).
      const std::vector<std::string> short_loops =
          simulated ? std::vector<std::string>{} : watch.EndInterval(now);
      if (setup.progress) {
        family->LogProgress(t, vehicle, rec.distance_m);
        for (const std::string& loop : short_loops) log::Warn(loop);
        const std::string counters = NonZeroCounters(watch.Counters());
        if (!counters.empty()) log::Info("         counters: " + counters);
      }
    }
  }
  const int64_t end_ns = MonotonicNs();
  if (!simulated) {
    for (const std::string& loop : watch.EndInterval(end_ns)) {
      if (setup.progress) log::Warn(loop);
    }
  }
  // The lap's clock and the approach's are kept apart: a run that never
  // reached the line was all approach.
  const double end_s = NsToS(end_ns - t0);
  const std::optional<double> lap_start = family->lap_start_s();
  rec.approach_s = lap_start.value_or(end_s);

  // Make safe: forces to zero (a physics world's leave the HAL at once too,
  // whatever its step is doing), the vehicle stopped or at neutral.
  haptic.hal().ZeroForces();
  family->RequestStop();
  vehicle.SendSafe();
  if (simulated) simulated->Stop();
  if (view_part) StopAndRecord(*view_part, result);
  family->Finish(result, setup.progress);
  // A lap stopped by a limit ran until the run ended, on the same clock as the
  // limits (the last state may be a few ms older): a lap stopped by its cap
  // shows the whole cap.
  if (lap_start && (result.outcome == Outcome::kTimeLimit || result.outcome == Outcome::kLapCap)) {
    rec.lap_time_s = std::max(rec.lap_time_s, end_s - *lap_start);
  }
  haptic.Stop();
  if (pump) pump->Stop();
  vehicle.Stop();

  RecordLinkFigures(haptic, vehicle, result);
  watch.Finish(rec);
  if (simulated) {
    RecordSimulatedFigures(*simulated, end_ns - t0, RealMonotonicNs() - wall_start_ns, result);
    result.cpu_s = ThreadCpuSeconds() - cpu_start_s;
  }
  return result;
}

}  // namespace haptel::mediator
