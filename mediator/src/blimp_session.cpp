#include "haptel/mediator/blimp_session.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/blimp_gesture.hpp"
#include "haptel/mediator/blimp/blimp_lap_timer.hpp"
#include "haptel/mediator/blimp/blimp_pilot.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/vehicle_link.hpp"

namespace haptel::mediator {

namespace {

/// The simulated pilot holds a hand where `goal` says.
void ActOn(haptics::SimDevice& device, haptics::Side side, const interfaces::HandGoal& goal) {
  device.SetOperatorTarget(side, goal.position);
  device.SetWristOrientation(side, goal.orientation);
  device.SetGlovePosture(side, goal.glove);
}

BlimpObservation Observe(double t_s, const msg::BlimpState& s) {
  BlimpObservation o;
  o.t_s = t_s;
  o.position = Eigen::Vector3d(s.x(), s.y(), s.z());
  o.yaw = s.yaw();
  o.pitch = s.pitch();
  o.roll = s.roll();
  o.velocity = Eigen::Vector3d(s.vx(), s.vy(), s.vz());
  o.airspeed = s.airspeed();
  o.contact = s.contact();
  o.impact_speed = s.impact_speed();
  return o;
}

void LogProgress(double t, const BlimpLapTimer& lap, const VehicleLink& link, const msg::BlimpState& s,
                 const BlimpCommand& command, const std::string& counters) {
  char line[300];
  std::snprintf(line, sizeof line,
                "%6.1f s  blimp  lap %5.1f s  gates %d/%d  obstacles %d  height %.1f m  airspeed %.1f m/s  "
                "power %.2f  helix %+.2f  rudder %+.2f  elevator %+.2f  tail %+.2f  rtt p50 %.2f ms  video %.1f fps",
                t, lap.lap_time_s(), lap.next_gate(), lap.gates_total(), lap.obstacles_touched(), s.z(),
                s.airspeed(), command.power, command.helix, command.rudder, command.elevator, command.tail_rotor,
                link.Rtt().Percentile(0.5) * 1e-3, link.video().Stats().fps);
  log::Info(line);
  if (!counters.empty()) log::Info("         counters: " + counters);
}

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
  interfaces::BlimpGestureInterface interface(*setup.blimp_interface);
  rec.interface = interface.name();

  // --- The haptic side: the hands are held before anything flies. ---
  HapticSide haptic(setup.device, setup.calibration, setup.gravity, run.op, setup.trace);
  std::unique_ptr<BlimpAutoPilot> pilot;
  if (setup.operator_kind == "auto") {
    if (haptic.sim() == nullptr) {
      throw ConfigError(setup.device.file.string() +
                        ": the automatic pilot moves the simulated arms (driver 'sim'); device '" +
                        setup.device.name + "' is flown by a person: use --operator person");
    }
    pilot = std::make_unique<BlimpAutoPilot>(course, BlimpPilotConfig{});
    const interfaces::HandTargets neutral = interface.HandTargetsFor({});
    for (int i = 0; i < haptics::kSides; ++i) {
      if (!neutral[i]) continue;
      haptic.sim()->Place(static_cast<haptics::Side>(i), neutral[i]->position);
      ActOn(*haptic.sim(), static_cast<haptics::Side>(i), *neutral[i]);
    }
  }
  haptic.Start(setup.progress);

  // --- The vehicle. ---
  VehicleLinkOptions link_options;
  link_options.vehicle = setup.vehicle;
  link_options.link = run.link;
  link_options.track_file = course.file;
  link_options.program = setup.vehicle_program;
  link_options.decode_video = false;  // nothing shows it yet
  VehicleLink vehicle(link_options);
  rec.vehicle_pid = vehicle.pid();
  if (setup.progress && vehicle.pid() != 0) {
    log::Info("vehicle '" + setup.vehicle.name + "' (" + setup.vehicle.kind + ") started, pid " +
              std::to_string(vehicle.pid()));
  }

  BlimpLapTimer lap(course);
  const int64_t t0 = MonotonicNs();
  LoopWatch watch(haptic, nullptr, vehicle, nullptr, t0);
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  const auto command_period_ns = static_cast<int64_t>(1e9 / setup.blimp_interface->command_rate_hz);
  int64_t next_command_ns = t0;
  int64_t next_progress_ns = t0 + SToNs(2.0);
  int64_t next_tick = t0;
  bool vehicle_up = false;
  const double startup_timeout_s = 15.0;
  msg::BlimpState last;
  BlimpCommand command;
  bool have_position = false;
  Eigen::Vector3d last_position = Eigen::Vector3d::Zero();
  double last_path_t = -1.0;
  bool touching = false;
  rec.path.reserve(16384);

  auto finish = [&](Outcome outcome, std::string message) {
    result.outcome = outcome;
    result.message = std::move(message);
    if (outcome == Outcome::kVehicleLost || outcome == Outcome::kVehicleDidNotStart ||
        outcome == Outcome::kDeviceLost) {
      log::Error(result.message + "; forces zeroed, blimp to neutral");
    }
  };

  for (;;) {
    SleepUntilNs(next_tick);
    next_tick += period_ns;
    const int64_t now = MonotonicNs();
    const double t = NsToS(now - t0);

    if (interrupted.load()) {
      finish(Outcome::kInterrupted, "interrupted by the operator");
      break;
    }
    if (haptic.lost()) {
      result.lost_detect_s = haptic.silent_s();
      finish(Outcome::kDeviceLost, "haptic device '" + setup.device.name + "' lost: an arm stopped answering");
      break;
    }
    if (!vehicle.ProcessAlive()) {
      result.lost_detect_s = vehicle_up ? NsToS(now - vehicle.last_received_ns()) : 0.0;
      finish(vehicle_up ? Outcome::kVehicleLost : Outcome::kVehicleDidNotStart,
             "vehicle '" + setup.vehicle.name + "' lost: process " + std::to_string(vehicle.pid()) + " " +
                 vehicle.ExitDescription());
      break;
    }
    std::string vehicle_fault;
    for (const auto& e : vehicle.blimp_inbox().Drain()) {
      const msg::BlimpState& s = e.state;
      if (s.fault() && vehicle_fault.empty()) vehicle_fault = s.fault_message();
      const double ts = NsToS(e.received_ns - t0);
      if (!vehicle_up) haptic.OnVehicleUp();
      vehicle_up = true;
      last = s;
      if (!s.pose_valid()) continue;
      const BlimpObservation o = Observe(ts, s);
      if (pilot) pilot->Observe(o);
      lap.Update(o);
      if (have_position) rec.distance_m += (o.position - last_position).norm();
      have_position = true;
      last_position = o.position;
      if (ts - last_path_t >= 0.05) {
        rec.path.push_back({ts, s.x(), s.y(), o.velocity.norm()});
        last_path_t = ts;
      }
      if (s.contact() && !touching) rec.contacts.push_back({ts, s.x(), s.y()});
      touching = s.contact();
    }
    if (!vehicle_fault.empty()) {
      finish(Outcome::kVehicleLost, "vehicle '" + setup.vehicle.name + "' stopped itself: " + vehicle_fault);
      break;
    }
    if (vehicle_up) {
      const double silent_s = NsToS(now - vehicle.last_received_ns());
      if (silent_s > run.vehicle_timeout_s) {
        result.lost_detect_s = silent_s;
        finish(Outcome::kVehicleLost, "vehicle '" + setup.vehicle.name + "' lost: no state for " +
                                          std::to_string(silent_s).substr(0, 4) + " s");
        break;
      }
    } else if (t > startup_timeout_s) {
      finish(Outcome::kVehicleDidNotStart, "vehicle '" + setup.vehicle.name + "' did not answer within " +
                                               std::to_string(static_cast<int>(startup_timeout_s)) +
                                               " s on domain " + std::to_string(run.link.domain_id));
      break;
    }

    // The pilot's hands and gaze; a person's head would come from the view.
    interfaces::HeadDirection head;
    if (pilot && vehicle_up) {
      const BlimpCommand intent = pilot->Decide(t);
      const interfaces::HandTargets targets = interface.HandTargetsFor(intent);
      for (int i = 0; i < haptics::kSides; ++i) {
        if (targets[i]) ActOn(*haptic.sim(), static_cast<haptics::Side>(i), *targets[i]);
      }
      head = {intent.camera_pan, intent.camera_tilt};
    }
    command = interface.Update(head, haptic.hal());
    if (now >= next_command_ns) {
      next_command_ns += command_period_ns;
      if (next_command_ns < now) next_command_ns = now;
      vehicle.Send(vehicle_up ? command : BlimpCommand{});
    }

    if (lap.crashed()) {
      finish(Outcome::kCrashed, "the blimp crashed: a contact at " +
                                    std::to_string(lap.crash_speed()).substr(0, 4) + " m/s (more than " +
                                    std::to_string(course.crash_speed).substr(0, 4) + " m/s)");
      break;
    }
    if (lap.completed()) {
      finish(Outcome::kCompleted, "landed: lap completed");
      break;
    }
    if (setup.time_limit_s > 0 && t > setup.time_limit_s) {
      finish(Outcome::kTimeLimit,
             "time limit of " + std::to_string(static_cast<int>(setup.time_limit_s)) + " s reached");
      break;
    }
    if (t > course.lap_cap_s) {
      finish(Outcome::kLapCap, "lap cap of " + std::to_string(static_cast<int>(course.lap_cap_s)) + " s reached");
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
  vehicle.Stop();

  const LoopStats servo_stats = haptic.Stats();
  const VideoStats v = vehicle.video().Stats();
  const Histogram& rtt = vehicle.Rtt();
  rec.completed = result.outcome == Outcome::kCompleted;
  rec.outcome = ToString(result.outcome);
  rec.lap_time_s = lap.lap_time_s();
  rec.gates_passed = lap.gates_passed();
  rec.gates_missed = lap.gates_missed();
  rec.obstacles_touched = lap.obstacles_touched();
  for (const BlimpGateSplit& split : lap.splits()) rec.splits.push_back({split.gate, split.passed, split.split_s});
  rec.servo_rate_hz = servo_stats.rate_hz;
  rec.servo_period_p99_us = servo_stats.period_p99_us;
  rec.command_rtt_ms_p50 = rtt.Percentile(0.5) * 1e-3;
  rec.command_rtt_ms_p99 = rtt.Percentile(0.99) * 1e-3;
  rec.video_frames = static_cast<int64_t>(v.frames);
  rec.video_fps = v.fps;
  rec.video_latency_ms_p50 = v.latency_ms_p50;
  result.servo_overruns = servo_stats.overruns;
  watch.Finish(rec);
  return result;
}

}  // namespace haptel::mediator
