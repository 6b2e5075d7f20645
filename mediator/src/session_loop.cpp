#include "session_loop.hpp"

#include <cmath>

#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/models/tread_drive.hpp"

namespace haptel::mediator {

void Finish(SessionResult& result, LoopEnd end, const char* made_safe) {
  result.outcome = end.outcome;
  result.message = std::move(end.message);
  if (end.lost_detect_s > 0.0) result.lost_detect_s = end.lost_detect_s;
  if (end.outcome == Outcome::kVehicleLost || end.outcome == Outcome::kVehicleDidNotStart ||
      end.outcome == Outcome::kDeviceLost) {
    log::Error(result.message + "; " + made_safe);
  } else if (end.outcome == Outcome::kLostControl) {
    log::Error(result.message);  // nothing this run sends makes it safe now
  }
}

std::optional<LoopEnd> CheckOperatorSide(const std::atomic<bool>& interrupted,
                                         const HapticSide& haptic, const std::string& device_name) {
  if (interrupted.load()) return LoopEnd{Outcome::kInterrupted, "interrupted by the operator"};
  if (haptic.lost()) {
    // Unplugged by the person: aborted, as a disconnected game controller is.
    if (const std::string line = haptic.unplugged(); !line.empty()) {
      return LoopEnd{Outcome::kAborted, "haptic device '" + device_name + "': " + line,
                     haptic.silent_s()};
    }
    return LoopEnd{Outcome::kDeviceLost,
                   "haptic device '" + device_name + "' lost: an arm stopped answering",
                   haptic.silent_s()};
  }
  return std::nullopt;
}

VehicleHealth::VehicleHealth(const std::string& vehicle_name, int domain_id, uint64_t session,
                             const link::WriterId& writer, double vehicle_timeout_s,
                             double startup_timeout_s, int64_t spawned_pid)
    : name_(vehicle_name),
      domain_id_(domain_id),
      session_(session),
      writer_(writer),
      timeout_s_(vehicle_timeout_s),
      startup_timeout_s_(startup_timeout_s),
      spawned_pid_(spawned_pid),
      host_(HostName()) {}

std::optional<LoopEnd> VehicleHealth::StrangerConflict() const {
  if (stranger_.empty()) return std::nullopt;
  return LoopEnd{
      Outcome::kConflict,
      "another vehicle answers as '" + name_ + "' on domain " + std::to_string(domain_id_) + " (" +
          stranger_ + ", not the vehicle this run started, pid " + std::to_string(spawned_pid_) +
          "): its states were not used; give each vehicle its own name (haptel-vehicle --name, "
          "haptel run --vehicle-name) or domain, or --attach to drive the one already running"};
}

std::optional<LoopEnd> VehicleHealth::CheckProcess(VehicleLink& vehicle, int64_t now_ns) {
  if (auto end = StrangerConflict()) return end;
  if (vehicle.VehiclesOnTopic() > 1) {
    if (conflict_since_ns_ == 0) conflict_since_ns_ = now_ns;
    if (NsToS(now_ns - conflict_since_ns_) >= kConflictAfter_s) {
      return LoopEnd{
          Outcome::kConflict,
          std::to_string(vehicle.VehiclesOnTopic()) + " vehicles answer as '" + name_ +
              "' on domain " + std::to_string(domain_id_) +
              ": their states would mix and both would obey; give each vehicle its own name "
              "(haptel-vehicle --name, haptel run --vehicle-name) or domain (one that has just "
              "ended may take a few seconds to leave the domain)"};
    }
  } else {
    conflict_since_ns_ = 0;
  }
  if (vehicle.ProcessAlive()) return std::nullopt;
  return LoopEnd{up_ ? Outcome::kVehicleLost : Outcome::kVehicleDidNotStart,
                 "vehicle '" + name_ + "' lost: process " + std::to_string(vehicle.pid()) + " " +
                     vehicle.ExitDescription(),
                 up_ ? NsToS(now_ns - vehicle.last_received_ns()) : 0.0};
}

bool VehicleHealth::OnState(bool fault, const std::string& fault_message, uint64_t owner_session,
                            const link::WriterId& owner_writer, const char* owner, int64_t now_ns) {
  if (fault && fault_.empty()) fault_ = fault_message;
  if (owner_writer == writer_) {
    had_control_ = true;
    refused_since_ns_ = 0;
  } else if (owner_writer.empty()) {
    refused_since_ns_ = 0;  // free: our next command takes it
  } else if (had_control_ || owner_session == session_) {
    // Another writer is obeyed after this run's was, or under this run's
    // session: this run's commands are not the ones obeyed. No grace: the
    // vehicle hands itself over only after its owner's release or silence.
    if (lost_control_.empty()) {
      lost_control_ =
          "vehicle '" + name_ + "' on domain " + std::to_string(domain_id_) +
          " obeys another writer's commands now, not this run's: " +
          (owner_session == session_
               ? "a participant that names this run's session (copied off the "
                 "link by someone on the domain), "
               : std::string()) +
          "'" + owner + "', writer " + owner_writer.ToString() +
          "; this run lost control of the vehicle (DDS Security, --security, keeps participants "
          "the deployment's CA does not vouch for off the link)";
    }
  } else if (refused_since_ns_ == 0) {
    refused_since_ns_ = now_ns;
    owner_ = owner;
  }
  const bool first = !up_;
  up_ = true;
  return first;
}

std::optional<LoopEnd> VehicleHealth::LostControl() const {
  if (lost_control_.empty()) return std::nullopt;
  return LoopEnd{Outcome::kLostControl, lost_control_};
}

std::optional<LoopEnd> VehicleHealth::CheckStates(const VehicleLink& vehicle, int64_t now_ns,
                                                  double t_s) {
  if (auto end = StrangerConflict()) return end;
  if (auto end = LostControl()) return end;
  if (!fault_.empty()) {
    std::string fault;
    fault.swap(fault_);
    return LoopEnd{Outcome::kVehicleLost, "vehicle '" + name_ + "' stopped itself: " + fault};
  }
  if (refused_since_ns_ != 0 && NsToS(now_ns - refused_since_ns_) >= kRefusedAfter_s) {
    return LoopEnd{Outcome::kRefused,
                   "vehicle '" + name_ + "' on domain " + std::to_string(domain_id_) +
                       " is driven by another operator (" + owner_ +
                       "): a vehicle obeys one operator at a time; wait until that run ends"};
  }
  if (up_) {
    const double silent_s = NsToS(now_ns - vehicle.last_received_ns());
    if (silent_s > timeout_s_) {
      return LoopEnd{Outcome::kVehicleLost,
                     "vehicle '" + name_ + "' lost: no state for " +
                         std::to_string(silent_s).substr(0, 4) + " s",
                     silent_s};
    }
  } else if (const std::string other = vehicle.ForeignStateType(); !other.empty()) {
    // Discovery names the type of every writer, matched or not: a vehicle
    // of the other family (a blimp under a robot's name) is told at once,
    // not after the start-up time-out.
    return LoopEnd{
        Outcome::kVehicleDidNotStart,
        "vehicle '" + name_ + "' on domain " + std::to_string(domain_id_) + " publishes " + other +
            " as its state, not a " + ToString(vehicle.family()) +
            "'s: is it another kind of vehicle (its file here says kind " + vehicle.kind() + ")?"};
  } else if (t_s > startup_timeout_s_) {
    std::string message = "vehicle '" + name_ + "' did not answer within " +
                          std::to_string(static_cast<int>(startup_timeout_s_)) + " s on domain " +
                          std::to_string(domain_id_);
    // Its camera speaks but its state never matched: a vehicle of the other
    // family (a blimp under a robot's name) publishes another state type.
    if (const uint64_t frames = vehicle.video().Stats().frames; frames > 0) {
      message += ": " + std::to_string(frames) + " camera frames arrived under that name but no " +
                 ToString(vehicle.family()) +
                 "'s state: is it another kind of vehicle (its file here says kind " +
                 vehicle.kind() + ")?";
    }
    return LoopEnd{Outcome::kVehicleDidNotStart, message};
  }
  return std::nullopt;
}

void RunTrace::Add(double t_s, double x, double y, double z, double speed, bool touching,
                   double driven_m) {
  // A contact the run starts in (the blimp resting on its pad) did not begin
  // during the run: only later onsets are contacts.
  if (!have_position_) touching_ = touching;
  if (have_position_) {
    record_.distance_m +=
        driven_m >= 0.0 ? driven_m
                        : std::sqrt((x - last_x_) * (x - last_x_) + (y - last_y_) * (y - last_y_) +
                                    (z - last_z_) * (z - last_z_));
  }
  have_position_ = true;
  last_x_ = x;
  last_y_ = y;
  last_z_ = z;
  if (t_s - last_path_t_ >= 0.05) {
    record_.path.push_back({t_s, x, y, speed});
    last_path_t_ = t_s;
  }
  if (touching && !touching_) record_.contacts.push_back({t_s, x, y});
  touching_ = touching;
}

bool CommandDue(int64_t& next_ns, int64_t now_ns, int64_t period_ns, bool changed) {
  if (changed) {
    next_ns = now_ns + period_ns;  // the period counts from the last command sent
    return true;
  }
  if (now_ns < next_ns) return false;
  next_ns += period_ns;
  if (next_ns < now_ns) next_ns = now_ns;
  return true;
}

bool LevelsChange(const TreadCommand& sent, const TreadCommand& now, int speed_levels) {
  return models::QuantiseCommand(sent.left, speed_levels) !=
             models::QuantiseCommand(now.left, speed_levels) ||
         models::QuantiseCommand(sent.right, speed_levels) !=
             models::QuantiseCommand(now.right, speed_levels);
}

std::optional<LoopEnd> CheckLimits(double t_s, std::optional<double> lap_start_s,
                                   double time_limit_s, double lap_limit_s, double lap_cap_s) {
  if (time_limit_s > 0 && t_s > time_limit_s) {
    return LoopEnd{
        Outcome::kTimeLimit,
        "time limit of " + std::to_string(static_cast<int>(time_limit_s)) + " s reached"};
  }
  const double lap_clock_s = lap_start_s ? t_s - *lap_start_s : t_s;
  // Said only when a limit is reached: the loop calls this every tick.
  const char* clock = lap_start_s ? " on the lap clock" : " before the start line";
  if (lap_limit_s > 0 && lap_clock_s > lap_limit_s) {
    return LoopEnd{Outcome::kTimeLimit,
                   "lap limit of " + JsonNumber(lap_limit_s) + " s reached" + clock};
  }
  if (lap_clock_s > lap_cap_s) {
    return LoopEnd{Outcome::kLapCap, "lap cap of " + std::to_string(static_cast<int>(lap_cap_s)) +
                                         " s reached" + clock};
  }
  return std::nullopt;
}

void RecordLinkFigures(const HapticSide& haptic, const VehicleLink& vehicle,
                       SessionResult& result) {
  RunRecord& rec = result.record;
  const LoopStats servo = haptic.Stats();
  const video::VideoStats v = vehicle.video().Stats();
  const Histogram& rtt = vehicle.Rtt();
  rec.completed = result.outcome == Outcome::kCompleted;
  rec.outcome = ToString(result.outcome);
  rec.servo_rate_hz = servo.rate_hz;
  rec.servo_period_p99_us = servo.period_p99_us;
  rec.command_rtt_ms_p50 = rtt.Percentile(0.5) * 1e-3;
  rec.command_rtt_ms_p99 = rtt.Percentile(0.99) * 1e-3;
  rec.video_frames = static_cast<int64_t>(v.frames);
  rec.video_fps = v.fps;
  rec.video_latency_ms_p50 = v.latency_ms_p50;
  rec.video_kbps = v.kbps;
  rec.video_stale_s = v.stale_s;
  result.servo_overruns = servo.overruns;
  const LinkCounts counts = vehicle.Counts();
  result.commands_sent = counts.commands_sent;
  result.states_received = counts.states_received;
  result.servo_arm_ticks = 0;
  for (const haptics::Side side : {haptics::Side::kLeft, haptics::Side::kRight})
    result.servo_arm_ticks += haptic.Counters(side).cycles;
}

}  // namespace haptel::mediator
