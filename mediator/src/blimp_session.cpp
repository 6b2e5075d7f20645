#include "haptel/mediator/blimp_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/blimp_gesture.hpp"
#include "haptel/interfaces/blimp_manual.hpp"
#include "haptel/mediator/blimp/blimp_lap_timer.hpp"
#include "haptel/mediator/blimp/blimp_pilot.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/operator.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "session_loop.hpp"

namespace haptel::mediator {

namespace {

BlimpObservation Observe(double t_s, const msg::BlimpState& s) {
  BlimpObservation o;
  o.t_s = t_s;
  o.position = Eigen::Vector3d(s.x(), s.y(), s.z());
  o.yaw = s.yaw();
  o.pitch = s.pitch();
  o.velocity = Eigen::Vector3d(s.vx(), s.vy(), s.vz());
  o.airspeed = s.airspeed();
  o.contact = s.contact();
  o.contacts = s.contacts();
  o.impact_speed = s.impact_speed();
  return o;
}

void LogProgress(double t, const BlimpLapTimer& lap, const VehicleLink& link, const msg::BlimpState& s,
                 const BlimpCommand& command, const std::string& counters) {
  char line[300];
  std::snprintf(line, sizeof line,
                "%6.1f s  blimp  lap %5.1f s  gates %d/%d  obstacles %d  at %.0f %.0f m  height %.1f m  airspeed %.1f m/s  "
                "power %.2f  helix %+.2f  rudder %+.2f  elevator %+.2f  tail %+.2f  camera %+.2f %+.2f rad  "
                "rtt p50 %.2f ms  video %.1f fps",
                t, lap.lap_time_s(), lap.next_gate(), lap.gates_total(), lap.obstacles_touched(), s.x(),
                s.y(), s.z(), s.airspeed(), command.power, command.helix, command.rudder, command.elevator, command.tail_rotor,
                s.outputs()[5], s.outputs()[6], link.Rtt().Percentile(0.5) * 1e-3, link.video().Stats().fps);
  log::Info(line);
  if (!counters.empty()) log::Info("         counters: " + counters);
}

/// What the blimp's view shows over the picture: the lap, the gates, the
/// last contact, the airspeed on the HUD's dial (full scale: the model's top
/// speed in still air) and a line of height and engine. Builds it without allocating.
class BlimpOverlay {
 public:
  BlimpOverlay(const SessionSetup& setup, std::string interface, int gates_total)
      : setup_(setup), interface_(std::move(interface)), gates_total_(gates_total) {}

  view::Overlay Make(double t, const BlimpLapTimer& lap, const msg::BlimpState& s, const BlimpCommand& c,
                     bool vehicle_up) {
    view::Overlay o = LapOverlay(setup_, interface_.c_str(), t, lap.lap_time_s(), lap.next_gate(), gates_total_,
                                 lap.obstacles_touched());
    // A new contact onset, not the blimp resting on its pad at the start.
    if (s.pose_valid() && contacts_seen_ < 0) contacts_seen_ = s.contacts();
    if (contacts_seen_ >= 0 && s.contacts() > static_cast<uint32_t>(contacts_seen_)) {
      contacts_seen_ = s.contacts();
      touched_ = true;
      std::snprintf(last_contact_, sizeof last_contact_, "%.1f m/s at %.1f s", s.impact_speed(), t);
    }
    if (!s.contact()) touched_ = false;
    std::snprintf(o.last_contact, sizeof o.last_contact, "%s", last_contact_);
    o.contact_now = touched_;
    o.hud = true;
    o.speed_mps = s.airspeed();
    o.speed_max_mps = setup_.vehicle.airship.StillAirTopSpeed();
    std::snprintf(o.status, sizeof o.status, "height %.1f m  power %.0f%%  helix %+.0f%%", s.z(), 100.0 * c.power,
                  100.0 * c.helix);
    if (!vehicle_up) {
      std::snprintf(o.message, sizeof o.message, "waiting for vehicle '%s'", setup_.vehicle.name.c_str());
    } else if (s.failsafe()) {
      std::snprintf(o.message, sizeof o.message, "failsafe: every channel at neutral");
    } else if (setup_.operator_kind == "person" && t < kHelpS) {
      std::snprintf(o.message, sizeof o.message, "%s", Help());
    }
    return o;
  }

 private:
  const char* Help() const {
    if (!setup_.blimp_manual) return "drag the mouse to look around, Home looks ahead, Esc ends";
    if (setup_.blimp_manual->input() == BlimpManualInput::kGamepad) {
      return "left stick power (sideways: tail rotor), right stick elevator/rudder, triggers climb";
    }
    return "W/S power, up/down climb, A/D turn, PgUp/PgDn elevator, space neutral, drag to look";
  }
  static constexpr double kHelpS = 15.0;
  const SessionSetup& setup_;
  std::string interface_;
  int gates_total_;
  int64_t contacts_seen_ = -1;  ///< contact onsets when the first pose came; -1: none yet
  bool touched_ = false;        ///< in a contact that began in flight (the border shows it)
  char last_contact_[40] = "";
};

}  // namespace

SessionResult RunBlimpSession(const SessionSetup& setup, const std::atomic<bool>& interrupted) {
  const RunConfig& run = setup.run;
  const BlimpCourseConfig& course = *setup.course;
  SessionResult result;
  RunRecord& rec = result.record;
  rec.started_wall_ns = WallNs();
  rec.config_name = run.name;
  rec.track = course.name;
  rec.vehicle = setup.vehicle.name;
  rec.vehicle_kind = setup.vehicle.kind;
  rec.gates_total = static_cast<int>(course.gates.size());
  rec.operator_kind = setup.operator_kind;
  rec.device = setup.device.name;
  // The gesture cockpit, or a person's keys or game controller.
  interfaces::InputBox input;
  std::optional<interfaces::BlimpGestureInterface> gesture;
  std::optional<interfaces::BlimpManualInterface> manual;
  if (setup.blimp_manual) {
    manual.emplace(*setup.blimp_manual, input.Load());
    rec.interface = manual->name();
  } else {
    gesture.emplace(*setup.blimp_interface);
    rec.interface = gesture->name();
  }
  const double command_rate_hz =
      manual ? setup.blimp_manual->command_rate_hz : setup.blimp_interface->command_rate_hz;

  // --- The haptic side: the hands are held before anything flies. ---
  HapticSide haptic(setup.device, setup.calibration, setup.gravity, run.op, setup.trace);
  std::unique_ptr<BlimpAutoPilot> pilot;
  if (setup.operator_kind == "auto") {
    if (!gesture) throw ConfigError("the automatic pilot flies the blimp gesture cockpit, not '" + rec.interface + "'");
    if (haptic.sim() == nullptr) {
      throw ConfigError(setup.device.file.string() +
                        ": the automatic pilot moves the simulated arms (driver 'sim'); device '" +
                        setup.device.name + "' is flown by a person: use --operator person");
    }
    pilot = std::make_unique<BlimpAutoPilot>(course, PilotKnowing(setup.vehicle.airship));
    PlaceHands(*haptic.sim(), gesture->HandTargetsFor({}));
  }
  haptic.Start(setup.progress);

  // --- The vehicle. ---
  VehicleLinkOptions link_options;
  link_options.vehicle = setup.vehicle;
  link_options.link = run.link;
  link_options.track_file = course.file;
  link_options.program = setup.vehicle_program;
  link_options.decode_video = run.video_decode && DecodesVideo(setup.view);
  VehicleLink vehicle(link_options);
  rec.vehicle_pid = vehicle.pid();
  if (setup.progress && setup.attach) {
    log::Info("attached to vehicle '" + setup.vehicle.name + "' on domain " + std::to_string(run.link.domain_id) +
              " (session " + std::to_string(vehicle.session()) + "): spawning none");
  }
  if (setup.progress && vehicle.pid() != 0) {
    log::Info("vehicle '" + setup.vehicle.name + "' (" + setup.vehicle.kind + ") started, pid " +
              std::to_string(vehicle.pid()));
  }

  // --- The view: the pilot camera's picture on a screen that turns with the
  // camera, the view turning with the head (mouse-look in the window). ---
  std::unique_ptr<SessionView> view_part;
  if (setup.view != ViewKind::kNone) {
    SessionView::Parts view_parts;
    view_parts.hal = &haptic.hal();
    view_parts.physics_config = &setup.physics;  // the tracked hands' size
    view_parts.video = &vehicle.video();
    view_parts.hands = {gesture.has_value(), gesture.has_value()};
    view::ViewOptions options = ViewOptionsFor(setup);
    options.screen = view::HeadTrackedScreen();
    view_part = std::make_unique<SessionView>(options, view_parts, input);
  }
  // A person's controller without a view: a thread of its own polls it.
  std::unique_ptr<view::InputPump> pump;
  if (manual && manual->input_kind() == BlimpManualInput::kGamepad && !view_part) {
    pump = std::make_unique<view::InputPump>(input);
  }
  BlimpOverlay overlay_feed(setup, rec.interface, static_cast<int>(course.gates.size()));

  BlimpLapTimer lap(course);
  const int64_t t0 = MonotonicNs();
  LoopWatch watch(haptic, nullptr, vehicle, view_part.get(), t0);
  int64_t next_live_ns = t0;
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  const auto command_period_ns = static_cast<int64_t>(1e9 / command_rate_hz);
  int64_t next_command_ns = t0;
  int64_t next_progress_ns = t0 + SToNs(2.0);
  int64_t next_tick = t0;
  VehicleHealth health(setup.vehicle.name, run.link.domain_id, vehicle.session(), run.vehicle_timeout_s);
  msg::BlimpState last;
  BlimpCommand command;
  RunTrace trace(rec);
  rec.path.reserve(16384);
  const auto finish = [&](LoopEnd end) { Finish(result, std::move(end), "forces zeroed, blimp to neutral"); };

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
    for (const auto& e : vehicle.blimp_inbox().Drain()) {
      const msg::BlimpState& s = e.state;
      const double ts = NsToS(e.received_ns - t0);
      if (health.OnState(s, e.received_ns)) haptic.OnVehicleUp();
      last = s;
      if (!s.pose_valid()) continue;
      const BlimpObservation o = Observe(ts, s);
      if (pilot) pilot->Observe(o);
      lap.Update(o);
      trace.Add(ts, s.x(), s.y(), s.z(), o.velocity.norm(), s.contact());
    }
    if (auto end = health.CheckStates(vehicle, now, t)) {
      finish(std::move(*end));
      break;
    }
    const bool vehicle_up = health.up();

    // The pilot's hands and gaze; a person's head turns with mouse-look.
    interfaces::HeadDirection head{person.head_pan, person.head_tilt};
    if (pilot) {
      head = {};
      if (vehicle_up) {
        const BlimpCommand intent = pilot->Decide(t);
        HoldHands(*haptic.sim(), gesture->HandTargetsFor(intent));
        head = {intent.camera_pan, intent.camera_tilt};
      }
    }
    command = manual ? manual->Update(t, person, haptic.hal()) : gesture->Update(head, haptic.hal());
    if (manual && manual->lost()) {
      finish({Outcome::kAborted, "the game controller was disconnected"});
      break;
    }
    if (CommandDue(next_command_ns, now, command_period_ns)) vehicle.Send(vehicle_up ? command : BlimpCommand{});
    if (view_part || setup.on_live) {
      const view::Overlay overlay = overlay_feed.Make(t, lap, last, command, vehicle_up);
      if (view_part) {
        view_part->Publish(overlay);
        // The screen hangs where the camera points as the vehicle applied it.
        view_part->Publish(view::Gaze{true, head.pan, head.tilt, last.outputs()[5], last.outputs()[6]});
      }
      if (setup.on_live && now >= next_live_ns) {
        next_live_ns = now + SToNs(0.5);
        setup.on_live(overlay);
      }
    }

    if (lap.crashed()) {
      finish({Outcome::kCrashed, "the blimp crashed: a contact at " + std::to_string(lap.crash_speed()).substr(0, 4) +
                                     " m/s (more than " + std::to_string(course.crash_speed).substr(0, 4) + " m/s)"});
      break;
    }
    if (lap.completed()) {
      finish({Outcome::kCompleted, "landed: lap completed"});
      break;
    }
    if (auto end = CheckLimits(t, setup.time_limit_s, course.lap_cap_s)) {
      finish(std::move(*end));
      break;
    }
    if (now >= next_progress_ns) {
      next_progress_ns += SToNs(2.0);
      const std::vector<std::string> short_loops = watch.EndInterval(now);
      if (setup.progress) {
        LogProgress(t, lap, vehicle, last, command, NonZeroCounters(watch.Counters()));
        for (const std::string& loop : short_loops) log::Warn(loop);
      }
    }
  }
  for (const std::string& loop : watch.EndInterval(MonotonicNs())) {
    if (setup.progress) log::Warn(loop);
  }

  // Make safe: forces to zero, every channel to neutral, the vehicle ended.
  haptic.hal().ZeroForces();
  vehicle.Send(BlimpCommand{});
  haptic.Stop();
  if (pump) pump->Stop();
  if (view_part) StopAndRecord(*view_part, result);
  vehicle.Stop();

  RecordLinkFigures(haptic, vehicle, result);
  rec.lap_time_s = lap.lap_time_s();
  rec.gates_passed = lap.gates_passed();
  rec.gates_missed = lap.gates_missed();
  rec.obstacles_touched = lap.obstacles_touched();
  for (const BlimpGateSplit& split : lap.splits()) rec.splits.push_back({split.gate, split.passed, split.split_s});
  watch.Finish(rec);
  return result;
}

}  // namespace haptel::mediator
