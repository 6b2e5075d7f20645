#include "haptel/udp/arm_server.hpp"

#include <poll.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "haptel/core/clock.hpp"
#include "haptel/haptics/force_field.hpp"

namespace haptel::haptics::udp {

namespace {
/// As the servo loop's velocity filter: the tracker is quantised.
constexpr double kVelocityFilter_s = 0.005;
}  // namespace

ArmUnits UnitsOf(const SimDevice& sim, Side side) {
  const SimArmTruth& t = sim.truth(side);
  ArmUnits u;
  u.tracker_scale = t.tracker_scale;
  u.tracker_offset = t.tracker_offset;
  u.force_slope = t.force_slope;
  u.force_limit_n = sim.config().force_limit;
  return u;
}

ArmServer::ArmServer(Device& arm, Side side, int fd, const ArmServerOptions& options,
                     const ArmUnits& units, Clock& clock)
    : sim_(arm),
      units_(units),
      side_(side),
      fd_(fd),
      options_(options),
      clock_(clock),
      session_timeout_ns_(SToNs(options.lost_after_s)),
      delay_ns_(SToNs(std::clamp(options.delay_s, 0.0, kMaxDelay_s))),
      arm_end_(ChannelEnd::kDevice, options.limits) {}

void ArmServer::Poll(int64_t wait_ns) {
  CheckWatchdog();
  if (wait_ns > 0) {
    pollfd p{fd_, POLLIN, 0};
    const timespec ts{static_cast<time_t>(wait_ns / 1'000'000'000),
                      static_cast<long>(wait_ns % 1'000'000'000)};
    if (::ppoll(&p, 1, &ts, nullptr) <= 0) return;
  }
  for (;;) {
    from_len_ = sizeof from_;
    const ssize_t n = ::recvfrom(fd_, rx_.data(), rx_.size(), MSG_DONTWAIT,
                                 reinterpret_cast<sockaddr*>(&from_), &from_len_);
    if (n < 0) break;
    Handle(static_cast<std::size_t>(n));
  }
}

void ArmServer::Handle(std::size_t size) {
  ++c_.datagrams;
  const DecodeStatus status = Decode(std::span<const uint8_t>(rx_.data(), size), msg_);
  if (status != DecodeStatus::kOk) {
    ++c_.malformed[static_cast<std::size_t>(status)];
    // A sound header with a type we do not know: say so, so a newer client sees why.
    if (status == DecodeStatus::kUnknownType) Reply(ErrorReply{ErrorCode::kUnsupported});
    return;  // anything else is not trusted enough to answer
  }
  const MessageType type = msg_.type();
  const bool request = type == MessageType::kWristRequest || type == MessageType::kGloveRequest;
  const bool command = type == MessageType::kWristForce || type == MessageType::kFingerForce;
  if (!request && !command) {
    ++c_.unexpected;
    return;
  }
  if (msg_.side != side_) {
    ++c_.wrong_side;
    if (request) Reply(ErrorReply{ErrorCode::kWrongSide});
    return;
  }
  CheckWatchdog();  // a client quiet for too long loses the arm (forces zeroed) before anyone takes
                    // over
  const bool same_peer = from_len_ == peer_len_ && std::memcmp(&from_, &peer_, peer_len_) == 0;
  if (session_ && !same_peer) {
    ++c_.busy;
    if (request) Reply(ErrorReply{ErrorCode::kBusy});
    return;
  }
  const int64_t now = clock_.NowNs();
  if (!session_) {
    session_ = true;
    peer_ = from_;
    peer_len_ = from_len_;
    StartSession();
  }
  last_heard_ns_ = now;
  if (request) ++c_.requests_by_version[msg_.version];
  if (const auto* p = std::get_if<WristRequest>(&msg_.payload)) {
    ++c_.wrist_requests;
    if (last_request_ns_ != 0 && now > last_request_ns_) {
      // The client's tick: what the controller's damping acts over until the next.
      period_s_ = static_cast<double>(now - last_request_ns_) * 1e-9;
    }
    last_request_ns_ = now;
    acted_this_tick_ = false;
    const WristRequest commands = *p;  // msg_ is reused by Reply
    QueueWrist(commands.wrist_force, msg_.version >= 2 ? &commands.energy : nullptr, now);
    ApplyFingers(commands.finger_forces);
    if (!Service(now)) {
      ++c_.device_lost;
      Reply(ErrorReply{ErrorCode::kDeviceLost});
      return;
    }
    // The newest reading at least delay_s old (the oldest kept, early on).
    const uint64_t kept = std::min<uint64_t>(reads_, kRing);
    uint64_t pick = reads_ - kept;
    for (uint64_t j = reads_; j > reads_ - kept; --j) {
      if (readings_[(j - 1) % kRing].t_ns <= now - delay_ns_) {
        pick = j - 1;
        break;
      }
    }
    const Reading& r = readings_[pick % kRing];
    WristReply reply{clock_.NowNs(), r.raw.position, r.raw.orientation, r.report};
    Reply(reply);
  } else if (std::holds_alternative<GloveRequest>(msg_.payload)) {
    ++c_.glove_requests;
    GloveRaw raw;
    if (sim_.ReadGlove(side_, now, raw) != DeviceStatus::kOk) {
      ++c_.device_lost;
      Reply(ErrorReply{ErrorCode::kDeviceLost});
      return;
    }
    Reply(GloveReply{clock_.NowNs(), raw.sensors, raw.grasp});
  } else if (const auto* w = std::get_if<WristForce>(&msg_.payload)) {
    const WristForce force = *w;
    // A stale one changes nothing: the arm is serviced with the next datagram.
    if (QueueWrist(force.command, msg_.version >= 2 ? &force.energy : nullptr, now) &&
        !Service(now)) {
      ++c_.device_lost;
    }
  } else if (const auto* f = std::get_if<FingerForce>(&msg_.payload)) {
    ApplyFingers(f->command);
  }
}

bool ArmServer::QueueWrist(const Vec3d& command, const EnergyReport* report, int64_t now) {
  if (has_wrist_seq_ && !SequenceAfter(msg_.sequence, wrist_seq_) && msg_.sequence != wrist_seq_) {
    ++c_.stale_commands;
    return false;
  }
  has_wrist_seq_ = true;
  wrist_seq_ = msg_.sequence;
  if (queued_ - applied_ >= kRing) {
    ++c_.delay_overflows;
    return false;
  }
  Command& q = queue_[queued_ % kRing];
  q.due_ns = now + delay_ns_;
  q.command = command;
  q.report = report != nullptr ? *report : EnergyReport{};
  ++queued_;
  return true;
}

void ArmServer::ApplyFingers(const std::array<double, kFingers>& command) {
  if (has_finger_seq_ && !SequenceAfter(msg_.sequence, finger_seq_) &&
      msg_.sequence != finger_seq_) {
    ++c_.stale_commands;
    return;
  }
  has_finger_seq_ = true;
  finger_seq_ = msg_.sequence;
  sim_.WriteFingerForces(side_, command);
  ++c_.forces_applied;
}

Vec3d ArmServer::Metres(const Vec3d& raw) const {
  Vec3d m{};
  for (int i = 0; i < 3; ++i) m[i] = units_.tracker_scale[i] * raw[i] + units_.tracker_offset[i];
  return m;
}

Vec3d ArmServer::Newtons(const Vec3d& command) const {
  Vec3d f{};
  for (int i = 0; i < 3; ++i) f[i] = units_.force_slope[i] * command[i];
  LimitForce(f, units_.force_limit_n);  // the arm saturates, whatever it is told
  return f;
}

bool ArmServer::Service(int64_t now) {
  // The arm to now, under the force it held: its port's motion.
  WristRaw raw;
  if (sim_.ReadWrist(side_, now, raw) != DeviceStatus::kOk) return false;
  const Vec3d p = Metres(raw.position);
  Vec3d dx{};
  const bool have_previous = reads_ > 0;
  const double dt = have_previous ? static_cast<double>(now - last_service_ns_) * 1e-9 : 0.0;
  for (int i = 0; i < 3; ++i) {
    dx[i] = have_previous ? p[i] - position_[i] : 0.0;
    if (dt > 0.0) velocity_[i] += dt / (kVelocityFilter_s + dt) * (dx[i] / dt - velocity_[i]);
  }
  position_ = p;
  last_service_ns_ = now;
  arm_end_.Observe(dx);

  // What is due: the newest command whose delay has passed, its report merged.
  bool fresh = false;
  while (applied_ != queued_ && queue_[applied_ % kRing].due_ns <= now) {
    const Command& q = queue_[applied_ % kRing];
    command_ = q.command;
    if (q.report.epoch != remote_.epoch && remote_seen_) {
      // The client restarted its end: both count from zero again.
      dissipated_before_ += arm_end_.dissipated_total_j();
      arm_end_.Reset();
      ++c_.epochs;
    }
    remote_ = Merge(remote_, q.report);
    remote_seen_ = true;
    ++applied_;
    fresh = true;
  }
  if (fresh) ++c_.forces_applied;

  Vec3d applied = command_;
  const bool active = options_.passivity && remote_seen_ && remote_.active;
  const Vec3d rendered = Newtons(command_);
  if (active) {
    Vec3d remote_in{};
    for (int i = 0; i < 3; ++i) remote_in[i] = remote_.energy_in[i] - remote_.charged[i];
    const TwoPortAction a = arm_end_.Control(rendered, remote_in, velocity_, period_s_);
    for (int i = 0; i < 3; ++i) applied[i] += a.damping_force[i] / units_.force_slope[i];
    if (a.acted) {
      // Counted once per client tick (its request and its one-way force both service the arm).
      if (!acted_this_tick_) ++acted_ticks_;
      acted_this_tick_ = true;
      for (int i = 0; i < 3; ++i) max_alpha_ = std::max(max_alpha_, a.alpha[i]);
    }
  }
  // The arm saturates: hold what it will really apply.
  const Vec3d total = Newtons(applied);
  Vec3d damping{};
  for (int i = 0; i < 3; ++i) damping[i] = total[i] - rendered[i];
  arm_end_.Hold(rendered, damping);
  sim_.WriteWristForce(side_, applied);
  written_ = applied;

  Reading& r = readings_[reads_ % kRing];
  r.t_ns = now;
  r.raw = raw;
  r.report = OwnReport();
  ++reads_;
  c_.passivity_ticks = acted_ticks_;
  c_.passivity_max_alpha = max_alpha_;
  c_.passivity_dissipated_j = dissipated_before_ + arm_end_.dissipated_total_j();
  return true;
}

EnergyReport ArmServer::OwnReport() const {
  EnergyReport e;
  e.active = options_.passivity && remote_seen_ && remote_.active;
  e.epoch = remote_.epoch;
  e.energy_in = arm_end_.energy_in();
  // The damping's work can be negative for a moment (it acts on the filtered
  // velocity); the report carries counters, never below zero.
  e.dissipated_j = std::max(0.0, arm_end_.dissipated_total_j());
  e.acted_ticks = acted_ticks_;
  e.max_alpha = max_alpha_;
  return e;
}

void ArmServer::Reply(const Payload& payload) {
  const Message reply{msg_.sequence, msg_.side, payload, msg_.version};
  const std::size_t size = Encode(reply, tx_);
  if (size == 0 || ::sendto(fd_, tx_.data(), size, 0, reinterpret_cast<const sockaddr*>(&from_),
                            from_len_) < 0) {
    ++c_.send_errors;
  }
}

void ArmServer::CheckWatchdog() {
  if (session_ && clock_.NowNs() - last_heard_ns_ >= session_timeout_ns_) {
    ZeroForces();
    session_ = false;
    ++c_.watchdog_trips;
  }
}

void ArmServer::StartSession() {
  has_wrist_seq_ = has_finger_seq_ = false;
  reads_ = 0;
  queued_ = applied_ = 0;
  command_ = Vec3d{};
  dissipated_before_ = c_.passivity_dissipated_j;
  arm_end_.Reset();
  remote_ = EnergyReport{};
  remote_seen_ = false;
  velocity_ = Vec3d{};
  last_request_ns_ = 0;
}

void ArmServer::ZeroForces() {
  command_ = written_ = Vec3d{};
  queued_ = applied_;
  sim_.WriteWristForce(side_, Vec3d{});
  sim_.WriteFingerForces(side_, std::array<double, kFingers>{});
}

}  // namespace haptel::haptics::udp
