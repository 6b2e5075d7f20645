#include "haptel/udp/udp_device.hpp"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"

namespace haptel::haptics {

namespace udp {

int64_t MonotonicClock::NowNs() { return MonotonicNs(); }

Clock::WaitResult MonotonicClock::WaitReadable(int fd, int64_t deadline_ns) {
  const int64_t remaining = deadline_ns - MonotonicNs();
  if (remaining <= 0) return WaitResult::kNotYet;
  pollfd p{fd, POLLIN, 0};
  const timespec ts{static_cast<time_t>(remaining / 1'000'000'000),
                    static_cast<long>(remaining % 1'000'000'000)};
  const int ready = ::ppoll(&p, 1, &ts, nullptr);
  if (ready > 0) return WaitResult::kReadable;
  if (ready < 0 && errno != EINTR) return WaitResult::kError;
  return WaitResult::kNotYet;
}

Clock& SystemClock() {
  static MonotonicClock clock;  // stateless: shared by every device and thread
  return clock;
}
}  // namespace udp

namespace {

constexpr const char* kSideNames[kSides] = {"left", "right"};
/// Datagrams a Drain reads at most, so a flood cannot hold the servo thread.
constexpr int kMaxDrain = 64;

/// Counters have one writer (the side's thread): a relaxed load + store is
/// enough and cheaper than a locked read-modify-write.
void Bump(std::atomic<uint64_t>& c) {
  c.store(c.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

/// Opens a non-blocking UDP socket connected to host:port; throws naming `where`.
udp::UniqueFd Connect(const std::string& host, int port, const std::string& where) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  const int rc = getaddrinfo(host.c_str(), service.c_str(), &hints, &found);
  if (rc != 0)
    throw std::runtime_error(where + ": cannot resolve host '" + host + "': " + gai_strerror(rc));
  const std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> list(found, &freeaddrinfo);
  std::string error = "no address";
  for (const addrinfo* a = list.get(); a != nullptr; a = a->ai_next) {
    udp::UniqueFd fd(
        ::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol));
    if (fd.get() < 0) {
      error = std::string("socket: ") + std::strerror(errno);
      continue;
    }
    if (::connect(fd.get(), a->ai_addr, a->ai_addrlen) == 0) return fd;
    error = std::string("connect: ") + std::strerror(errno);
  }
  throw std::runtime_error(where + ": cannot open a socket: " + error);
}

template <std::size_t N>
bool AllFinite(const std::array<double, N>& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

}  // namespace

uint64_t UdpCounters::malformed_total() const {
  uint64_t total = 0;
  for (uint64_t m : malformed) total += m;
  return total;
}

UdpCounters& UdpCounters::operator+=(const UdpCounters& o) {
  requests += o.requests;
  replies += o.replies;
  timeouts += o.timeouts;
  retries += o.retries;
  unanswered += o.unanswered;
  stale += o.stale;
  unexpected += o.unexpected;
  for (std::size_t i = 0; i < malformed.size(); ++i) malformed[i] += o.malformed[i];
  for (std::size_t i = 0; i < errors.size(); ++i) errors[i] += o.errors[i];
  forces_sent += o.forces_sent;
  invalid_commands += o.invalid_commands;
  socket_errors += o.socket_errors;
  lost_transitions += o.lost_transitions;
  recoveries += o.recoveries;
  return *this;
}

UdpDevice::UdpDevice(const DeviceConfig& config, udp::Clock& clock)
    : clock_(clock),
      lost_after_ns_(SToNs(Validated(config).udp.lost_after_s)),
      timeout_ns_(SToNs(config.udp.timeout_s)),
      retries_(config.udp.retries) {
  // DeviceConfig::ValidateOrThrow (above) requires a port for every side
  // used when the driver is udp: this device is that driver.
  if (config.driver != kDriver) {
    throw std::invalid_argument("UdpDevice: the config's driver is '" + config.driver +
                                "', not udp");
  }
  const std::string file =
      config.file.empty() ? "device '" + config.name + "'" : config.file.string();
  description_.name = config.name;
  description_.has_side = config.sides;
  description_.wrist_force_limit = config.safety.wrist_force_limit;
  description_.finger_force_limit = config.safety.finger_force_limit;
  description_.has_glove = config.has_glove;
  description_.has_grasp = config.has_grasp;
  const int64_t now = clock_.NowNs();
  for (int i = 0; i < kSides; ++i) {
    if (!config.sides[i]) continue;
    const UdpArmEndpoint& arm = config.udp.arms[i];
    const std::string where = file + ": key 'udp." + kSideNames[i] + "' (" + kSideNames[i] +
                              " arm at " + arm.host + ":" + std::to_string(arm.port) + ")";
    sides_[i].socket = Connect(arm.host, arm.port, where);
    sides_[i].last_valid_ns = now;
  }
}

DeviceStatus UdpDevice::ReadWrist(Side side, int64_t now_ns, WristRaw& out) {
  SideState& s = sides_[Index(side)];
  if (s.socket.get() < 0) return DeviceStatus::kLost;
  Drain(side, s);
  const uint32_t sequence = NextSequence(s);
  const uint16_t version = s.version.load(std::memory_order_relaxed);
  const udp::Message request{
      sequence, side, udp::WristRequest{s.wrist_command, s.finger_command, s.local}, version};
  const std::size_t size = udp::Encode(request, s.tx);  // commands were sanitised when stored
  Bump(s.counters.requests);
  const Wait wait = Transact(side, s, size, sequence, udp::MessageType::kWristReply);
  if (wait == Wait::kReply) {
    if (const auto* reply = std::get_if<udp::WristReply>(&s.reply.payload)) {
      out.t_ns = now_ns;
      out.position = reply->position;
      out.orientation = reply->orientation;
      // A report of an earlier epoch predates our restart: its counts are not ours.
      if (s.reply.version >= 2 && reply->energy.epoch == s.local.epoch) {
        s.remote = udp::Merge(s.remote, reply->energy);
      }
    }
  }
  return Outcome(s, wait);
}

DeviceStatus UdpDevice::ReadGlove(Side side, int64_t now_ns, GloveRaw& out) {
  SideState& s = sides_[Index(side)];
  if (s.socket.get() < 0) return DeviceStatus::kLost;
  Drain(side, s);
  const uint32_t sequence = NextSequence(s);
  const udp::Message request{sequence, side, udp::GloveRequest{},
                             s.version.load(std::memory_order_relaxed)};
  const std::size_t size = udp::Encode(request, s.tx);
  Bump(s.counters.requests);
  const Wait wait = Transact(side, s, size, sequence, udp::MessageType::kGloveReply);
  if (wait == Wait::kReply) {
    if (const auto* reply = std::get_if<udp::GloveReply>(&s.reply.payload)) {
      out.t_ns = now_ns;
      out.sensors = reply->sensors;
      out.grasp = reply->grasp;
    }
  }
  return Outcome(s, wait);
}

DeviceStatus UdpDevice::WriteWristForce(Side side, const Vec3d& command) {
  SideState& s = sides_[Index(side)];
  if (s.socket.get() < 0) return DeviceStatus::kLost;
  if (AllFinite(command)) {
    s.wrist_command = command;
  } else {
    s.wrist_command = Vec3d{};  // never send what the server must reject: zero is safe
    Bump(s.counters.invalid_commands);
  }
  SendOneWay(s, udp::Message{NextSequence(s), side, udp::WristForce{s.wrist_command, s.local},
                             s.version.load(std::memory_order_relaxed)});
  return s.lost.load(std::memory_order_relaxed) ? DeviceStatus::kLost : DeviceStatus::kOk;
}

DeviceStatus UdpDevice::WriteFingerForces(Side side, const std::array<double, kFingers>& command) {
  SideState& s = sides_[Index(side)];
  if (s.socket.get() < 0) return DeviceStatus::kLost;
  bool invalid = false;
  for (int f = 0; f < kFingers; ++f) {
    const bool ok = std::isfinite(command[f]) && command[f] >= 0.0;
    s.finger_command[f] = ok ? command[f] : 0.0;
    invalid = invalid || !ok;
  }
  if (invalid) Bump(s.counters.invalid_commands);
  SendOneWay(s, udp::Message{NextSequence(s), side, udp::FingerForce{s.finger_command},
                             s.version.load(std::memory_order_relaxed)});
  return s.lost.load(std::memory_order_relaxed) ? DeviceStatus::kLost : DeviceStatus::kOk;
}

void UdpDevice::SendOneWay(SideState& s, const udp::Message& message) {
  const std::size_t size = udp::Encode(message, s.tx);
  if (size == 0) return;  // cannot happen: values are sanitised
  if (::send(s.socket.get(), s.tx.data(), size, 0) < 0) {
    Bump(s.counters.socket_errors);
  } else {
    Bump(s.counters.forces_sent);
  }
}

UdpDevice::Wait UdpDevice::Transact(Side side, SideState& s, std::size_t size, uint32_t sequence,
                                    udp::MessageType type) {
  // A lost side is probed with a single attempt per call, so a dead server
  // costs the servo thread one timeout per cycle, not (1 + retries).
  const int attempts = s.lost.load(std::memory_order_relaxed) ? 1 : 1 + retries_;
  for (int attempt = 0; attempt < attempts; ++attempt) {
    if (attempt > 0) Bump(s.counters.retries);
    // Retries re-send the same datagram (same sequence): a late reply to any
    // attempt answers the request.
    if (::send(s.socket.get(), s.tx.data(), size, 0) < 0) Bump(s.counters.socket_errors);
    const Wait wait = AwaitReply(side, s, sequence, type, clock_.NowNs() + timeout_ns_);
    if (wait != Wait::kTimeout) return wait;
    Bump(s.counters.timeouts);
  }
  Bump(s.counters.unanswered);
  return Wait::kTimeout;
}

UdpDevice::Wait UdpDevice::AwaitReply(Side side, SideState& s, uint32_t sequence,
                                      udp::MessageType type, int64_t deadline_ns) {
  for (;;) {
    if (clock_.NowNs() >= deadline_ns) return Wait::kTimeout;
    const udp::Clock::WaitResult ready = clock_.WaitReadable(s.socket.get(), deadline_ns);
    if (ready == udp::Clock::WaitResult::kError) return Wait::kTimeout;
    if (ready == udp::Clock::WaitResult::kNotYet) continue;  // the deadline check ends the wait
    for (;;) {
      const ssize_t n = ::recv(s.socket.get(), s.rx.data(), s.rx.size(), 0);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
          Bump(s.counters.socket_errors);
        break;
      }
      if (Accept(side, s, static_cast<std::size_t>(n), sequence, type)) {
        return s.reply.type() == udp::MessageType::kError ? Wait::kError : Wait::kReply;
      }
    }
  }
}

void UdpDevice::Drain(Side side, SideState& s) {
  for (int i = 0; i < kMaxDrain; ++i) {
    const ssize_t n = ::recv(s.socket.get(), s.rx.data(), s.rx.size(), 0);
    if (n < 0) {
      if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) Bump(s.counters.socket_errors);
      return;
    }
    // Nothing is outstanding between calls: sequence 0 is never sent, so any
    // well-formed reply here is stale (late or duplicate).
    Accept(side, s, static_cast<std::size_t>(n), 0, udp::MessageType::kWristReply);
  }
}

bool UdpDevice::Accept(Side side, SideState& s, std::size_t size, uint32_t sequence,
                       udp::MessageType type) {
  const udp::DecodeStatus status =
      udp::Decode(std::span<const uint8_t>(s.rx.data(), size), s.reply);
  if (status != udp::DecodeStatus::kOk) {
    Bump(s.counters.malformed[static_cast<std::size_t>(status)]);
    return false;
  }
  if (s.reply.sequence != sequence || sequence == 0) {
    Bump(s.counters.stale);
    return false;
  }
  if (s.reply.side != side) {
    Bump(s.counters.unexpected);
    return false;
  }
  if (const auto* error = std::get_if<udp::ErrorReply>(&s.reply.payload)) {
    Bump(s.counters.errors[static_cast<std::size_t>(error->code)]);
    return true;
  }
  if (s.reply.type() != type) {
    Bump(s.counters.unexpected);
    return false;
  }
  Bump(s.counters.replies);
  return true;
}

DeviceStatus UdpDevice::Outcome(SideState& s, Wait wait) {
  const int64_t now = clock_.NowNs();
  if (wait == Wait::kReply || wait == Wait::kError) {
    // Any valid answer (an ERROR too) shows the server speaks this version.
    if (!s.negotiated) s.version.store(s.reply.version, std::memory_order_relaxed);
    s.negotiated = true;
  } else if (!s.negotiated) {
    // Unanswered before any answer: perhaps a server of the other version,
    // which drops ours unread. Try the other for the next request.
    const uint16_t v = s.version.load(std::memory_order_relaxed);
    s.version.store(v == udp::kVersion ? udp::kMinVersion : udp::kVersion,
                    std::memory_order_relaxed);
  }
  if (wait == Wait::kReply) {
    s.last_valid_ns = now;
    if (s.lost.exchange(false, std::memory_order_relaxed)) Bump(s.counters.recoveries);
    return DeviceStatus::kOk;
  }
  bool lose = now - s.last_valid_ns >= lost_after_ns_;
  if (const auto* error = std::get_if<udp::ErrorReply>(&s.reply.payload);
      wait == Wait::kError && error != nullptr && error->code == udp::ErrorCode::kDeviceLost) {
    lose = true;  // the server says its arm is gone: no reason to wait
  }
  if (lose) {
    if (!s.lost.exchange(true, std::memory_order_relaxed)) Bump(s.counters.lost_transitions);
    return DeviceStatus::kLost;
  }
  return s.lost.load(std::memory_order_relaxed) ? DeviceStatus::kLost : DeviceStatus::kNoData;
}

UdpCounters UdpDevice::Counters(Side side) const {
  const AtomicCounters& c = sides_[Index(side)].counters;
  const auto get = [](const std::atomic<uint64_t>& a) { return a.load(std::memory_order_relaxed); };
  UdpCounters out;
  out.requests = get(c.requests);
  out.replies = get(c.replies);
  out.timeouts = get(c.timeouts);
  out.retries = get(c.retries);
  out.unanswered = get(c.unanswered);
  out.stale = get(c.stale);
  out.unexpected = get(c.unexpected);
  for (std::size_t i = 0; i < out.malformed.size(); ++i) out.malformed[i] = get(c.malformed[i]);
  for (std::size_t i = 0; i < out.errors.size(); ++i) out.errors[i] = get(c.errors[i]);
  out.forces_sent = get(c.forces_sent);
  out.invalid_commands = get(c.invalid_commands);
  out.socket_errors = get(c.socket_errors);
  out.lost_transitions = get(c.lost_transitions);
  out.recoveries = get(c.recoveries);
  return out;
}

UdpCounters UdpDevice::Counters() const {
  UdpCounters total = Counters(Side::kLeft);
  total += Counters(Side::kRight);
  return total;
}

bool UdpDevice::LinkPassivity(Side side, LinkEnergy& remote) {
  const SideState& s = sides_[Index(side)];
  if (s.version.load(std::memory_order_relaxed) < 2 || !s.remote.active ||
      s.remote.epoch != s.local.epoch) {
    return false;
  }
  remote.energy_in = s.remote.energy_in;
  remote.charged = s.remote.charged;
  remote.dissipated_j = s.remote.dissipated_j;
  remote.acted_ticks = s.remote.acted_ticks;
  remote.max_alpha = s.remote.max_alpha;
  return true;
}

void UdpDevice::SetLinkEnergy(Side side, const LinkEnergy& local) {
  udp::EnergyReport& e = sides_[Index(side)].local;
  e.active = true;
  e.energy_in = local.energy_in;
  e.charged = local.charged;
  e.dissipated_j = local.dissipated_j;
  e.acted_ticks = local.acted_ticks;
  e.max_alpha = local.max_alpha;
}

void UdpDevice::RestartLinkEnergy(Side side) {
  SideState& s = sides_[Index(side)];
  const uint32_t epoch = s.local.epoch + 1 != 0 ? s.local.epoch + 1 : 1;
  s.local = udp::EnergyReport{};
  s.local.epoch = epoch;
  s.remote = udp::EnergyReport{};
}

uint16_t UdpDevice::ProtocolVersion(Side side) const {
  return sides_[Index(side)].version.load(std::memory_order_relaxed);
}

bool UdpDevice::Lost(Side side) const {
  return sides_[Index(side)].lost.load(std::memory_order_relaxed);
}

}  // namespace haptel::haptics
