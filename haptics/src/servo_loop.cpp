#include "haptel/haptics/servo_loop.hpp"

#include <pthread.h>
#include <sys/mman.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/calibrated_units.hpp"
#include "haptel/haptics/force_field.hpp"
#include "haptel/haptics/gravity.hpp"
#include "haptel/haptics/trace.hpp"

namespace haptel::haptics {

namespace {
/// Velocity low-pass time constant: the tracker is quantised (tens of µm), so
/// a raw 1 ms difference is noise; 5 ms keeps damping smooth and responsive.
constexpr double kVelocityFilter_s = 0.005;

/// The wrist force the set-point asks for at the arm's position and velocity,
/// by port: the interface's force field, and the proxy coupling with the
/// direct force. Each port is watched by the passivity controller apart.
struct SetpointForce {
  Vec3d field{};
  Vec3d coupling{};
};

/// Locks the process's pages as they are touched (MCL_ONFAULT), not every
/// mapping at once: with MCL_FUTURE alone each thread started later (DDS's,
/// a study console's workers) had its whole 8 MB stack locked in RAM, about
/// 180 MB over a trial's threads. What the servo loop touches is resident by
/// then (its buffers are made and filled before Start) or prefaulted by its
/// threads (PrefaultStack). A kernel without MCL_ONFAULT (before 4.4) gets
/// the old lock.
bool LockMemory() {
  if (mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0) return true;
  return mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
}

/// Touches the stack a servo thread may use, so that under MCL_ONFAULT its
/// pages are faulted in and locked here, not in a tick.
[[gnu::noinline]] void PrefaultStack() {
  constexpr size_t kBytes = 128 * 1024;
  unsigned char stack[kBytes];
  for (size_t i = 0; i < kBytes; i += 4096) stack[i] = 0;
  asm volatile("" : : "r"(stack) : "memory");  // the writes are kept: the compiler sees a use
}

SetpointForce ComposeSetpointForce(const ForceSetpoint& sp, const Vec3d& p, const Vec3d& v) {
  SetpointForce f;
  f.field = EvaluateForceField(sp.field, p, v);
  for (int i = 0; i < 3; ++i) {
    if (sp.coupling_enabled) {
      f.coupling[i] =
          sp.coupling_stiffness * (sp.coupling_target[i] - p[i]) - sp.coupling_damping * v[i];
    }
    f.coupling[i] += sp.wrist_force[i];
  }
  return f;
}

}  // namespace

ServoLoop::ServoLoop(Device& device, Hal& hal, const DeviceConfig& config,
                     const DeviceCalibration& calibration, const GravityGrid* gravity)
    : device_(device),
      hal_(hal),
      config_(Validated(config)),
      calibration_(Validated(calibration)),
      gravity_(gravity),
      observe_link_(config_.servo.passivity && device.HasLink()) {
  const DeviceDescription& d = device.description();
  for (int i = 0; i < kSides; ++i) {
    arms_[i] = std::make_unique<Arm>(
        ForceSafety(config.safety, d.wrist_force_limit, d.finger_force_limit));
    arms_[i]->passivity = ArmPassivity(config.servo, observe_link_);
  }
}

ServoLoop::~ServoLoop() { Stop(); }

void ServoLoop::Tick(Side side, int64_t now_ns) {
  Arm& arm = *arms_[Index(side)];
  ServoCounters& c = arm.counters;
  ++c.cycles;
  arm.cue_felt = false;
  ReadSlowChannels(arm, side, now_ns);
  TrackWrist(arm, side, now_ns);
  // The session file's sample of this tick (servo_tap.hpp): what every tick has.
  const auto tracked_sample = [&] {
    ServoSample s;
    s.t_ns = now_ns;
    s.cycle = c.cycles;
    s.side = static_cast<uint8_t>(Index(side));
    s.tracked_position = arm.previous_position;
    s.tracked_orientation = arm.wrist.orientation;
    return s;
  };
  if (!arm.connected || !arm.have_previous) {
    arm.published.Store(c);
    // A tick all the same: no forces, the wrist if read.
    if (tap_ != nullptr) tap_->Push(tracked_sample());
    return;  // lost (forces zeroed), or nothing to compute forces from yet
  }

  const double period_s =
      arm.last_tick_ns != 0 ? static_cast<double>(now_ns - arm.last_tick_ns) * 1e-9 : 0.0;
  arm.last_tick_ns = now_ns;
  // The position the forces are computed at: the arm's, or with the link's
  // admittance the arm's plus the offset that returns a deficit.
  Vec3d p = arm.previous_position;
  arm.passivity.ObserveLink(device_, side, arm.displacement, period_s, p, c);

  // Forces from the latest set-point, at full rate whatever the feeders' rates.
  if (!hal_.TrySetpoint(side, arm.setpoint)) ++c.setpoint_read_fallbacks;
  const ForceSetpoint& sp = arm.setpoint;
  device_.SetpointHint(side, sp);
  const SetpointForce ports = ComposeSetpointForce(sp, p, arm.velocity);
  Vec3d from_setpoint{};
  for (int i = 0; i < 3; ++i) from_setpoint[i] = ports.field[i] + ports.coupling[i];
  // A cue (a fleet's switch) is felt on top of whatever the interface asks,
  // outside the passivity ports: it is a short open-loop pulse, not a field.
  if (Hal::Cue cue; hal_.TryCue(side, cue) && now_ns < cue.until_ns) {
    for (int i = 0; i < 3; ++i) from_setpoint[i] += cue.force[i];
    arm.cue_felt = true;
  }
  arm.passivity.DampPorts(ports.field, ports.coupling, arm.displacement, arm.velocity, period_s,
                          from_setpoint, c);
  Vec3d local{};
  if (gravity_ != nullptr)
    local[2] = gravity_->Evaluate(arm.previous_position);  // the arm's own weight
  Vec3d wrist{};
  std::array<double, kFingers> fingers = sp.finger_forces;
  arm.safety.Apply(now_ns, sp.stamp_ns, from_setpoint, local, wrist, fingers);

  arm.passivity.ReportLink(device_, side, wrist, c);
  WriteForces(arm, side, now_ns, wrist, fingers);
  c.safety = arm.safety.counters();
  arm.published.Store(c);
  if (tap_ != nullptr) {
    ServoSample s = tracked_sample();
    s.coupling = sp.coupling_enabled;
    s.period_s = period_s;
    s.proxy_position = sp.coupling_target;
    s.field_force = ports.field;
    s.wrist_force = wrist;
    s.finger_forces = fingers;
    s.passivity_energy_j = arm.passivity.energy_j();
    s.passivity_dissipated_j = c.passivity_dissipated_j;
    tap_->Push(s);
  }
}

/// The glove and grasp strings, every `slow_channel_divider`-th cycle.
void ServoLoop::ReadSlowChannels(Arm& arm, Side side, int64_t now_ns) {
  const DeviceDescription& d = device_.description();
  if ((d.has_glove || d.has_grasp) &&
      arm.cycle % static_cast<uint64_t>(config_.servo.slow_channel_divider) == 0) {
    if (device_.ReadGlove(side, now_ns, arm.glove) == DeviceStatus::kOk) {
      hal_.PublishGlove(side, arm.glove);
      if (trace_ != nullptr) trace_->Push(TraceRecord::FromGlove(side, arm.glove));
      ++arm.counters.slow_reads;
    }
  }
  ++arm.cycle;
}

/// The wrist's reading: published, and the arm's motion (position,
/// displacement, filtered velocity) updated from it; a lost arm handled.
void ServoLoop::TrackWrist(Arm& arm, Side side, int64_t now_ns) {
  const DeviceStatus status = device_.ReadWrist(side, now_ns, arm.wrist);
  if (status == DeviceStatus::kLost) {
    OnArmLost(arm, side);
    return;
  }
  if (!arm.connected) {
    arm.connected = true;
    arm.safety.OnConnect(now_ns);
    hal_.PublishLost(side, false);
  }
  if (status != DeviceStatus::kOk) {
    ++arm.counters.no_data_ticks;
    arm.displacement = Vec3d{};
    return;
  }
  hal_.PublishWrist(side, arm.wrist);
  hal_.PublishPresence(side, device_.Presence(side));
  const ArmCalibration& cal = calibration_.arms[Index(side)];
  if (PseudoHapticReport shown; device_.PseudoHaptics(side, shown)) {
    shown.target = TrackerToMetres(cal, shown.target);
    shown.hand = TrackerToMetres(cal, shown.hand);
    for (int i = 0; i < 3; ++i) {
      shown.force[i] *= cal.force_slope[i];
      shown.shake[i] *= cal.tracker_scale[i];
    }
    hal_.PublishPseudoHaptics(side, shown);
    // A shake started: one record, so a trace can time it from the contact.
    if (trace_ != nullptr && shown.shakes != arm.shakes_traced) {
      arm.shakes_traced = shown.shakes;
      trace_->Push(TraceRecord::FromShake(side, shown));
    }
  }
  if (trace_ != nullptr) trace_->Push(TraceRecord::FromWrist(side, arm.wrist));
  const Vec3d p = TrackerToMetres(cal, arm.wrist.position);
  for (int i = 0; i < 3; ++i)
    arm.displacement[i] = arm.have_previous ? p[i] - arm.previous_position[i] : 0.0;
  if (arm.have_previous && now_ns > arm.previous_ns) {
    const double dt = static_cast<double>(now_ns - arm.previous_ns) * 1e-9;
    const double alpha = dt / (kVelocityFilter_s + dt);
    for (int i = 0; i < 3; ++i) {
      arm.velocity[i] += alpha * ((p[i] - arm.previous_position[i]) / dt - arm.velocity[i]);
    }
  }
  arm.previous_position = p;
  arm.previous_ns = now_ns;
  arm.have_previous = true;
}

void ServoLoop::OnArmLost(Arm& arm, Side side) {
  ++arm.counters.device_lost_ticks;
  if (arm.connected) {
    arm.connected = false;
    arm.safety.OnLost();
    hal_.PublishLost(side, true);
  }
  // Zero force, whatever the set-points say; a lost device may not hear it.
  device_.WriteWristForce(side, Vec3d{});
  device_.WriteFingerForces(side, {});
  arm.have_previous = false;
  arm.last_tick_ns = 0;
  arm.passivity.OnLost(device_, side);
}

/// The forces in the device's units, and the newtons to the HAL.
void ServoLoop::WriteForces(Arm& arm, Side side, int64_t now_ns, const Vec3d& wrist,
                            const std::array<double, kFingers>& fingers) {
  const ArmCalibration& cal = calibration_.arms[Index(side)];
  ServoCounters& c = arm.counters;
  if (device_.WriteWristForce(side, NewtonsToCommand(cal, wrist)) != DeviceStatus::kOk)
    ++c.write_failures;
  if (device_.description().has_grasp) {
    std::array<double, kFingers> finger_commands{};
    for (int k = 0; k < kFingers; ++k) finger_commands[k] = FingerNewtonsToCommand(cal, fingers[k]);
    if (device_.WriteFingerForces(side, finger_commands) != DeviceStatus::kOk) ++c.write_failures;
  }
  hal_.PublishForces(side, {now_ns, wrist, fingers});
}

void ServoLoop::Start() {
  if (running_.exchange(true)) return;
  stop_requested_.store(false);
  stop_latched_ = false;
  if (config_.servo.lock_memory) memory_locked_ = LockMemory();
  two_threads_ =
      config_.servo.two_sided && device_.HasSide(Side::kLeft) && device_.HasSide(Side::kRight);
  rendezvous_ = std::make_unique<std::barrier<Completion>>(two_threads_ ? 2 : 1, Completion{this});
  period_ns_ = static_cast<int64_t>(std::llround(1e9 / config_.servo.rate_hz));
  anchor_ns_ = MonotonicNs() + 2 * period_ns_;
  cycle_ = 0;
  threads_[0] = std::thread([this] { RunThread(0); });
  if (two_threads_) threads_[1] = std::thread([this] { RunThread(1); });
}

void ServoLoop::Stop() {
  stop_requested_.store(true);
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
  if (memory_locked_) {
    munlockall();
    memory_locked_ = false;
  }
  running_.store(false);
}

void ServoLoop::EndCycle() noexcept {
  stop_latched_ = stop_requested_.load();
  ++cycle_;
  const int64_t behind = MonotonicNs() - (anchor_ns_ + static_cast<int64_t>(cycle_) * period_ns_);
  if (behind > 10 * period_ns_) {
    // Too far behind to catch up: re-anchor and count the lost cycles.
    const int64_t skipped = behind / period_ns_;
    anchor_ns_ += skipped * period_ns_;
    for (LoopMeter& m : meters_) m.RecordSkipped(static_cast<uint64_t>(skipped));
  }
}

void ServoLoop::RunThread(int thread_index) {
  const char* name = !two_threads_ ? "servo" : (thread_index == 0 ? "servo-left" : "servo-right");
  pthread_setname_np(pthread_self(), name);
  LoopMeter& meter = meters_[thread_index];
  meter.SetRealtime(TryRealtime(config_.servo.realtime_priority));
  if (memory_locked_) PrefaultStack();
  // The right arm runs half a period after the left: staggered device I/O.
  const int64_t phase = thread_index == 1 ? period_ns_ / 2 : 0;
  int64_t previous_start = 0;
  for (;;) {
    const int64_t next = anchor_ns_ + static_cast<int64_t>(cycle_) * period_ns_ + phase;
    SleepUntilNs(next);
    const int64_t start = MonotonicNs();
    meter.RecordStart(start, next, period_ns_);
    bool cue_felt = false;
    if (two_threads_) {
      Tick(static_cast<Side>(thread_index), start);
      cue_felt = arms_[thread_index]->cue_felt;
    } else {
      for (int i = 0; i < kSides; ++i) {
        const auto side = static_cast<Side>(i);
        if (!device_.HasSide(side)) continue;
        Tick(side, i == 0 ? start : MonotonicNs());
        cue_felt = cue_felt || arms_[i]->cue_felt;
      }
    }
    // The period that ended at this tick's start, counted as the cue's when
    // this tick rendered it (its first tick included: the cue was set while
    // the loop slept towards it).
    if (cue_felt && previous_start != 0) {
      cue_periods_[thread_index].Record(static_cast<double>(start - previous_start) * 1e-3);
    }
    previous_start = start;
    rendezvous_->arrive_and_wait();  // both arms finish the cycle together
    if (stop_latched_) break;
  }
}

LoopStats ServoLoop::Stats(Side side) const {
  return meters_[two_threads_ ? Index(side) : 0].Stats();
}

LoopStats ServoLoop::Stats() const {
  const LoopStats a = meters_[0].Stats();
  if (!two_threads_) return a;
  const LoopStats b = meters_[1].Stats();
  return a.rate_hz <= b.rate_hz ? a : b;
}

const Histogram& ServoLoop::period_histogram(Side side) const {
  return meters_[two_threads_ ? Index(side) : 0].period_histogram();
}

const Histogram& ServoLoop::cue_period_histogram(Side side) const {
  return cue_periods_[two_threads_ ? Index(side) : 0];
}

ServoCounters ServoLoop::Counters(Side side) const { return arms_[Index(side)]->published.Load(); }

}  // namespace haptel::haptics
