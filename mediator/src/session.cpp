#include "haptel/mediator/session.hpp"

#include <cmath>
#include <cstdio>
#include <deque>
#include <memory>
#include <mutex>
#include <sstream>

#include "haptel/core/clock.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/calibration_procedure.hpp"
#include "haptel/haptics/gravity.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/mediator/auto_operator.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/mediator/video_receiver.hpp"

namespace haptel::mediator {

std::string ToString(Outcome outcome) {
  switch (outcome) {
    case Outcome::kCompleted: return "completed";
    case Outcome::kLapCap: return "lap cap";
    case Outcome::kVehicleLost: return "vehicle lost";
    case Outcome::kVehicleDidNotStart: return "vehicle did not start";
    case Outcome::kInterrupted: return "interrupted";
  }
  return "unknown";
}

namespace {

/// Vehicle states as they arrive (DDS thread), drained by the session loop.
class StateInbox {
 public:
  struct Entry {
    msg::VehicleState state;
    int64_t received_ns;
  };
  void Push(const msg::VehicleState& s) {
    const int64_t now = MonotonicNs();
    std::lock_guard lock(mutex_);
    // Round trip of the command this state echoes, minus the time it waited
    // at the vehicle: no shared clock needed.
    if (s.last_command_seq() != 0 && s.last_command_seq() != last_echo_seq_) {
      last_echo_seq_ = s.last_command_seq();
      rtt_.Record(static_cast<double>(now - s.last_command_sent_ns() - s.last_command_age_ns()) * 1e-3);
    }
    entries_.push_back({s, now});
    last_received_ns_ = now;
  }
  std::deque<Entry> Drain() {
    std::lock_guard lock(mutex_);
    std::deque<Entry> out;
    out.swap(entries_);
    return out;
  }
  int64_t last_received_ns() const {
    std::lock_guard lock(mutex_);
    return last_received_ns_;
  }
  const Histogram& rtt() const { return rtt_; }

 private:
  mutable std::mutex mutex_;
  std::deque<Entry> entries_;
  int64_t last_received_ns_ = 0;
  uint64_t last_echo_seq_ = 0;
  Histogram rtt_{10.0, 20000};  // µs bins up to 200 ms
};

/// The simulated person holds a hand as `goal` says.
void ActOn(haptics::SimDevice& device, haptics::Side side, const interfaces::HandGoal& goal) {
  device.SetOperatorTarget(side, goal.position);
  device.SetWristOrientation(side, goal.orientation);
  device.SetGlovePosture(side, goal.glove);
}

}  // namespace

SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted) {
  const RunConfig& run = setup.run;
  const Track track(setup.track);
  SessionResult result;
  RunRecord& rec = result.record;
  rec.started_wall_ns = WallNs();
  rec.config_name = run.name;
  rec.track = setup.track.name;
  rec.interface = setup.cockpit ? setup.cockpit->name : setup.gesture.name;
  rec.vehicle = setup.vehicle.name;
  rec.gates_total = static_cast<int>(track.gates().size());

  // Haptic side first: the hand is held at neutral before anything moves.
  haptics::SimDevice device(setup.device, run.op);
  DeviceCalibration calibration = setup.calibration;
  if (setup.device.calibration.empty()) {
    // No calibration file: calibrate the simulated device now, unattended,
    // as `haptel calibrate --auto` would (a fraction of a second).
    std::ostringstream quiet;
    haptics::CalibrationOptions options;
    options.auto_mode = true;
    calibration = haptics::RunCalibration(device, options, quiet);
  }
  haptics::Hal hal(calibration);
  // The interface, and the physics world when the interface's controls or
  // the scene have bodies: the hands the interface uses become proxies.
  const CockpitConfig* cockpit_config = setup.cockpit ? &*setup.cockpit : nullptr;
  const Scene* scene = setup.scene ? &*setup.scene : nullptr;
  std::unique_ptr<SessionPhysics> physics_side;
  std::unique_ptr<interfaces::MediatorInterface> interface_owner;
  const interfaces::CockpitInterface* cockpit = nullptr;
  if (cockpit_config == nullptr) interface_owner = std::make_unique<interfaces::GestureInterface>(setup.gesture);
  std::array<bool, haptics::kSides> hands{true, true};  // a cockpit needs both
  if (interface_owner) {
    const interfaces::HandTargets used = interface_owner->HandTargetsFor({});
    for (int i = 0; i < haptics::kSides; ++i) hands[i] = used[i].has_value();
  }
  physics_side = SessionPhysics::CreateIfNeeded(setup.physics, hands, cockpit_config, scene);
  if (cockpit_config != nullptr) {
    auto owned = std::make_unique<interfaces::CockpitInterface>(*cockpit_config, *physics_side->port);
    cockpit = owned.get();
    interface_owner = std::move(owned);
  }
  interfaces::MediatorInterface& interface = *interface_owner;
  const double command_rate_hz = setup.cockpit ? setup.cockpit->command_rate_hz : setup.gesture.command_rate_hz;
  // Hands at neutral — or, for controls to grasp, open above them.
  for (int i = 0; i < haptics::kSides; ++i) {
    const auto side = static_cast<haptics::Side>(i);
    if (auto neutral = interface.HandTargetsFor({})[i]) {
      interfaces::HandGoal start = *neutral;
      for (int k = 0; k < 3; ++k) start.position[k] += start.approach[k];
      start.glove = {};
      device.Place(side, start.position);
      ActOn(device, side, start);
    }
  }
  // Declared before the loop so it outlives the loop's threads.
  std::unique_ptr<haptics::TraceWriter> trace;
  if (!setup.trace.empty()) trace = std::make_unique<haptics::TraceWriter>(setup.trace);
  std::unique_ptr<haptics::GravityGrid> gravity;
  if (setup.gravity) gravity = std::make_unique<haptics::GravityGrid>(*setup.gravity);
  haptics::ServoLoop servo(device, hal, setup.device, calibration, gravity.get());
  servo.SetTrace(trace.get());
  servo.Start();
  if (physics_side) physics_side->world->Start(hal);
  if (setup.progress) {
    // Give the threads a moment to try for SCHED_FIFO, then say once what they could not get.
    SleepUntilNs(MonotonicNs() + SToNs(0.02));
    if (setup.device.servo.realtime_priority > 0 && !servo.Stats().realtime) {
      log::Info("servo loop runs without SCHED_FIFO (no permission); timing may jitter under load");
    }
    if (setup.device.servo.lock_memory && !servo.memory_locked()) {
      log::Info("servo loop runs without locked memory (mlockall refused); page faults may delay it");
    }
  }

  std::unique_ptr<ChildProcess> vehicle;
  if (!setup.vehicle_program.empty()) {
    vehicle = std::make_unique<ChildProcess>(
        setup.vehicle_program.string(),
        std::vector<std::string>{"--config", setup.vehicle.file.string(), "--track",
                                 setup.track.file.string(), "--name", setup.vehicle.name,
                                 "--domain", std::to_string(run.link.domain_id)});
    rec.vehicle_pid = vehicle->pid();
    if (setup.progress) log::Info("vehicle '" + setup.vehicle.name + "' started, pid " + std::to_string(vehicle->pid()));
  }

  StateInbox inbox;
  link::Participant participant(run.link, "haptel-mediator");
  link::CommandWriter commands(participant, link::TopicName(setup.vehicle.name, "command"),
                               link::Profile::kCommand);
  link::StateReader states(participant, link::TopicName(setup.vehicle.name, "state"),
                           link::Profile::kState, [&inbox](const msg::VehicleState& s) { inbox.Push(s); });
  VideoReceiver video(participant, link::TopicName(setup.vehicle.name, "video"), run.video_decode);

  AutoOperator op(track, run.op, setup.vehicle.drive);
  LapTimer lap(track);
  msg::DriveCommand command;
  uint64_t command_seq = 0;
  const int64_t t0 = MonotonicNs();
  const auto period_ns = static_cast<int64_t>(1e9 / run.session_rate_hz);
  const auto command_period_ns = static_cast<int64_t>(1e9 / command_rate_hz);
  int64_t next_command_ns = t0;
  int64_t next_progress_ns = t0 + SToNs(2.0);
  int64_t next_tick = t0;
  bool vehicle_up = false;
  const double startup_timeout_s = 15.0;
  interfaces::VehicleFeedback feedback;
  interfaces::MotorCommand motors;

  auto finish = [&](Outcome outcome, std::string message) {
    result.outcome = outcome;
    result.message = std::move(message);
    // Said at once: the clean-up that follows may take a while.
    if (outcome == Outcome::kVehicleLost || outcome == Outcome::kVehicleDidNotStart) {
      log::Error(result.message + "; forces zeroed");
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
    if (vehicle && !vehicle->Alive()) {
      result.lost_detect_s = vehicle_up ? NsToS(now - inbox.last_received_ns()) : 0.0;
      finish(vehicle_up ? Outcome::kVehicleLost : Outcome::kVehicleDidNotStart,
             "vehicle '" + setup.vehicle.name + "' lost: process " + std::to_string(vehicle->pid()) +
                 " " + vehicle->ExitDescription());
      break;
    }
    for (const auto& e : inbox.Drain()) {
      const msg::VehicleState& s = e.state;
      const double ts = NsToS(e.received_ns - t0);
      vehicle_up = true;
      if (s.pose_valid()) {
        op.Observe({ts, s.x(), s.y(), s.heading(), s.bumper_left(), s.bumper_right()});
        lap.Update(ts, Vec2(s.x(), s.y()));
      }
      lap.UpdateContact(ts, s.bumper_left() || s.bumper_right());
      feedback = {s.bumper_left(), s.bumper_right(), s.speed()};
    }
    if (vehicle_up) {
      const double silent_s = NsToS(now - inbox.last_received_ns());
      if (silent_s > run.vehicle_timeout_s) {
        result.lost_detect_s = silent_s;
        finish(Outcome::kVehicleLost, "vehicle '" + setup.vehicle.name + "' lost: no state for " +
                                          std::to_string(silent_s).substr(0, 4) + " s");
        break;
      }
    } else if (t > startup_timeout_s) {
      finish(Outcome::kVehicleDidNotStart,
             "vehicle '" + setup.vehicle.name + "' did not answer within " +
                 std::to_string(static_cast<int>(startup_timeout_s)) + " s on domain " +
                 std::to_string(run.link.domain_id));
      break;
    }

    // The simulated person acts on the device; the interface reads the device.
    if (vehicle_up) {
      const interfaces::HandTargets targets = op.Act(t, interface);
      for (int i = 0; i < haptics::kSides; ++i) {
        if (targets[i]) ActOn(device, static_cast<haptics::Side>(i), *targets[i]);
      }
      if (result.grasp_s == 0.0 && op.grasped(t) && cockpit != nullptr) result.grasp_s = t;
    }
    motors = interface.Update(t, feedback, hal);
    if (now >= next_command_ns) {
      next_command_ns += command_period_ns;
      if (next_command_ns < now) next_command_ns = now + command_period_ns;
      command.seq(++command_seq);
      command.left(static_cast<float>(vehicle_up ? motors.left : 0.0));
      command.right(static_cast<float>(vehicle_up ? motors.right : 0.0));
      command.sent_ns(MonotonicNs());
      commands.Write(command);
    }

    if (lap.completed()) {
      finish(Outcome::kCompleted, "lap completed");
      break;
    }
    if (t > setup.track.lap_cap_s) {
      finish(Outcome::kLapCap, "lap cap of " + std::to_string(static_cast<int>(setup.track.lap_cap_s)) +
                                   " s reached");
      break;
    }
    if (setup.progress && now >= next_progress_ns) {
      next_progress_ns += SToNs(2.0);
      const VideoStats v = video.Stats();
      char line[200];
      std::snprintf(line, sizeof line, "%6.1f s  lap %5.1f s  gates %d/%d  obstacles %d  rtt p50 %.2f ms  video %.1f fps",
                    t, lap.lap_time_s(), lap.next_gate(), lap.gates_total(), lap.obstacles_touched(),
                    inbox.rtt().Percentile(0.5) * 1e-3, v.fps);
      log::Info(line);
      if (cockpit != nullptr) {
        const interfaces::CockpitControls& c = cockpit->controls();
        const interfaces::HudState& h = cockpit->hud();
        char hud[80] = "";
        if (setup.cockpit->hud) {
          std::snprintf(hud, sizeof hud, "  HUD %.2f m/s%s%s%s", h.speed, h.turn_left ? " <" : "", h.turn_right ? " >" : "",
                        h.throttle_locked ? " locked" : "");
        }
        std::snprintf(line, sizeof line, "         wheel %+.2f rad%s  throttle %+.3f m%s  motors %+.2f %+.2f%s", c.wheel_angle,
                      c.wheel_held ? " (held)" : "", c.throttle, c.throttle_held ? " (held)" : "", motors.left, motors.right, hud);
        log::Info(line);
      }
    }
  }

  // Make safe: forces to zero, motors stopped, vehicle process ended.
  hal.ZeroForces();
  command.seq(++command_seq);
  command.left(0.0F);
  command.right(0.0F);
  command.sent_ns(MonotonicNs());
  commands.Write(command);
  if (physics_side) {
    physics_side->world->Stop();
    const LoopStats p = physics_side->world->Stats();
    const physics::PhysicsCounters counters = physics_side->world->Counters();
    result.physics_rate_hz = p.rate_hz;
    result.physics_period_p99_us = p.period_p99_us;
    result.physics_step_max_us = counters.max_step_us;
    result.physics_hand_resets = counters.hand_resets;
    result.scene_bodies = static_cast<int>(physics_side->scene.nodes.size());
  }
  if (cockpit != nullptr && result.grasp_s == 0.0) result.grasp_s = -1.0;
  servo.Stop();
  if (vehicle) vehicle->Terminate();

  const LoopStats servo_stats = servo.Stats();
  const VideoStats v = video.Stats();
  rec.completed = result.outcome == Outcome::kCompleted;
  rec.outcome = ToString(result.outcome);
  rec.lap_time_s = lap.lap_time_s();
  rec.gates_passed = lap.gates_passed();
  rec.gates_missed = lap.gates_missed();
  rec.obstacles_touched = lap.obstacles_touched();
  rec.splits = lap.splits();
  rec.servo_rate_hz = servo_stats.rate_hz;
  rec.servo_period_p99_us = servo_stats.period_p99_us;
  rec.command_rtt_ms_p50 = inbox.rtt().Percentile(0.5) * 1e-3;
  rec.command_rtt_ms_p99 = inbox.rtt().Percentile(0.99) * 1e-3;
  rec.video_frames = static_cast<int64_t>(v.frames);
  rec.video_fps = v.fps;
  rec.video_latency_ms_p50 = v.latency_ms_p50;
  result.servo_overruns = servo_stats.overruns;
  return result;
}

}  // namespace haptel::mediator
