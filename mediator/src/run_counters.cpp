#include "haptel/mediator/run_counters.hpp"

#include <cmath>
#include <cstdio>

#include "haptel/core/clock.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/vehicle_link.hpp"

namespace haptel::mediator {

namespace {
/// A counter of a figure kept in SI units: `value` in thousandths, rounded.
uint64_t Milli(double value) {
  return value > 0.0 ? static_cast<uint64_t>(std::llround(value * 1e3)) : 0;
}
}  // namespace

std::vector<RunCounter> CollectCounters(const HapticSide& haptic, const SessionPhysics* physics,
                                        const VehicleLink& vehicle, const SessionView* view) {
  const haptics::ServoCounters servo = haptic.Counters();
  physics::PhysicsCounters world;
  uint64_t physics_overruns = 0;
  if (physics != nullptr && physics->world) {
    world = physics->world->Counters();
    physics_overruns = physics->world->Stats().overruns;
  }
  const LinkCounts link = vehicle.Counts();
  const auto fault = vehicle.FaultCounts();
  const video::VideoStats video = vehicle.video().Stats();
  const uint64_t record_dropped = view != nullptr ? view->Stats().record_dropped : 0;
  return {
      {"servo_overruns", haptic.Stats().overruns},
      {"servo_device_lost_ticks", servo.device_lost_ticks},
      {"servo_no_data_ticks", servo.no_data_ticks},
      {"servo_write_failures", servo.write_failures},
      {"servo_forces_non_finite", servo.safety.non_finite},
      {"servo_forces_clamped", servo.safety.clamped},
      {"servo_forces_rate_limited", servo.safety.rate_limited},
      {"servo_setpoint_stale_ticks", servo.safety.stale_ticks},
      {"servo_setpoint_read_fallbacks", servo.setpoint_read_fallbacks},
      {"servo_passivity_ticks", servo.passivity_ticks},
      {"servo_passivity_left_mj",
       Milli(haptic.Counters(haptics::Side::kLeft).passivity_dissipated_j)},
      {"servo_passivity_right_mj",
       Milli(haptic.Counters(haptics::Side::kRight).passivity_dissipated_j)},
      {"servo_passivity_alpha_max_mns_m", Milli(servo.passivity_max_alpha)},
      // The two-port across a device's link (udp, protocol v2): the device's end, as its server
      // reports it.
      {"servo_passivity_link_ticks", servo.passivity_link_ticks},
      {"servo_passivity_device_ticks", servo.passivity_device_ticks},
      {"servo_passivity_device_mj", Milli(servo.passivity_device_dissipated_j)},
      {"servo_passivity_device_alpha_max_mns_m", Milli(servo.passivity_device_max_alpha)},
      {"physics_overruns", physics_overruns},
      {"physics_hand_resets", world.hand_resets},
      {"physics_body_resets", world.body_resets},
      {"physics_invalid_samples", world.invalid_samples},
      {"vehicle_watchdog_trips", link.watchdog_trips},
      {"vehicle_commands_dropped", link.commands_dropped},
      {"vehicle_video_feedback_refused", link.video_feedback_refused},
      {"link_states_missed", link.states_missed},
      {"link_queue_dropped", fault.queue_dropped},
      {"link_queue_dropped_bytes", fault.queue_dropped_bytes},
      {"video_frames_dropped", video.dropped},
      {"video_decode_failures", video.decode_failures},
      {"video_frames_lost", video.frames_lost},
      {"video_frames_skipped", video.frames_skipped},
      {"video_key_frame_requests", video.key_frame_requests},
      {"view_record_dropped", record_dropped},
  };
}

std::string NonZeroCounters(const std::vector<RunCounter>& counters) {
  std::string out;
  for (const RunCounter& c : counters) {
    if (c.value == 0) continue;
    if (!out.empty()) out += ", ";
    out += c.name + " " + std::to_string(c.value);
  }
  return out;
}

RateCheck::RateCheck(std::string name, double target_hz, uint64_t ticks, int64_t now_ns)
    : name_(std::move(name)), target_hz_(target_hz), ticks_(ticks), start_ns_(now_ns) {}

std::optional<std::string> RateCheck::EndInterval(uint64_t ticks, int64_t now_ns) {
  const double span_s = NsToS(now_ns - start_ns_);
  if (span_s < kMinIntervalS) return std::nullopt;
  const double rate_hz = static_cast<double>(ticks - ticks_) / span_s;
  ticks_ = ticks;
  start_ns_ = now_ns;
  return Judge(rate_hz);
}

std::optional<std::string> RateCheck::EndRun(const LoopStats& run) {
  if (run.ticks < 2 || run.elapsed_s < kMinIntervalS) return std::nullopt;
  return Judge(run.rate_hz);
}

std::optional<std::string> RateCheck::Judge(double rate_hz) {
  if (target_hz_ <= 0.0 || rate_hz >= kRateShortShare * target_hz_) return std::nullopt;
  short_ = true;
  char line[120];
  std::snprintf(line, sizeof line, "%s %.0f Hz of %.0f Hz: cannot keep its rate", name_.c_str(),
                rate_hz, target_hz_);
  return std::string(line);
}

}  // namespace haptel::mediator

namespace haptel::mediator {

LoopWatch::LoopWatch(const HapticSide& haptic, const SessionPhysics* physics,
                     const VehicleLink& vehicle, const SessionView* view, int64_t now_ns)
    : haptic_(haptic),
      physics_(nullptr),
      vehicle_(vehicle),
      view_(view),
      servo_("servo", haptic.target_hz(), haptic.Stats().ticks, now_ns) {
  AddPhysics(physics, now_ns);
}

void LoopWatch::AddPhysics(const SessionPhysics* physics, int64_t now_ns) {
  if (physics == nullptr || !physics->world) return;
  physics_ = physics;
  const physics::PhysicsWorld& world = *physics_->world;
  physics_rate_.emplace("physics", 1.0 / world.config().step_s, world.Stats().ticks, now_ns);
}

std::vector<std::string> LoopWatch::EndInterval(int64_t now_ns) {
  std::vector<std::string> lines;
  if (auto line = servo_.EndInterval(haptic_.Stats().ticks, now_ns)) lines.push_back(*line);
  if (physics_rate_) {
    if (auto line = physics_rate_->EndInterval(physics_->world->Stats().ticks, now_ns)) {
      lines.push_back(*line);
    }
  }
  return lines;
}

std::vector<RunCounter> LoopWatch::Counters() const {
  return CollectCounters(haptic_, physics_, vehicle_, view_);
}

void LoopWatch::Finish(RunRecord& rec) {
  servo_.EndRun(haptic_.Stats());
  rec.servo_target_hz = servo_.target_hz();
  rec.servo_rate_short = servo_.short_of_rate();
  if (physics_rate_) {
    const LoopStats stats = physics_->world->Stats();
    physics_rate_->EndRun(stats);
    rec.physics_rate_hz = stats.rate_hz;
    rec.physics_target_hz = physics_rate_->target_hz();
    rec.physics_rate_short = physics_rate_->short_of_rate();
  }
  rec.counters = Counters();
}

}  // namespace haptel::mediator
