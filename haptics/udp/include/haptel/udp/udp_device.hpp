#pragma once
/// @file The `udp` device: exoskeleton arms each served by their own computer
/// over the protocol in haptics/udp/PROTOCOL.md (one haptel-device-server per arm
/// on a test machine).
///
/// One connected UDP socket per configured side. ReadWrist is one round trip
/// (WRIST_REQUEST carrying the force commands in force → WRIST_REPLY);
/// ReadGlove is one round trip (GLOVE_REQUEST → GLOVE_REPLY); the Write calls
/// store the command and send it at once as a one-way WRIST_FORCE /
/// FINGER_FORCE datagram, so they never wait. A request waits up to
/// `udp.timeout_s` per attempt and is re-sent (same sequence number) up to
/// `udp.retries` times. A reply is accepted only if it decodes cleanly and
/// echoes the outstanding request's sequence number, side and expected type;
/// anything else is counted and the wait goes on until the deadline.
/// A side that has had no valid reply for `udp.lost_after_s` (or whose server
/// reports ERROR device_lost) answers kLost until a valid reply comes back.
///
/// Threads: each side's calls come from that side's servo thread and touch
/// only that side's socket, buffers and state; counters are atomics that any
/// thread may read. Reads and writes allocate nothing.
///
/// Time: every timeout, retry and lost decision reads a udp::Clock, which also
/// does the waiting for a reply. The product's is CLOCK_MONOTONIC and ppoll();
/// a test passes a fake whose time moves only when the test (or a wait that
/// nothing will answer) moves it, so retry counts and the lost transition do
/// not depend on how loaded the machine is.
#include <array>
#include <atomic>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/core/unique_fd.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/udp/udp_protocol.hpp"

namespace haptel::haptics {

namespace udp {
/// The shared file descriptor owner (core/unique_fd.hpp).
using UniqueFd = haptel::UniqueFd;

/// What a UdpDevice knows of time. Each side's servo thread calls it, both at
/// once in two-sided mode, so an implementation is stateless or thread-safe;
/// it must not allocate, lock or block beyond WaitReadable's deadline (it runs
/// in the servo loop).
class Clock {
 public:
  enum class WaitResult {
    kReadable,  ///< `fd` has something to read (or an error to report)
    kNotYet,    ///< nothing yet: the deadline passed, or the wait was interrupted
    kError,     ///< the wait itself failed; the caller gives up on this attempt
  };
  virtual ~Clock() = default;
  /// Now, in nanoseconds on this clock.
  virtual int64_t NowNs() = 0;
  /// Waits until `fd` is readable or this clock reaches `deadline_ns`.
  /// kNotYet may come early (EINTR): the caller re-reads NowNs() and decides.
  virtual WaitResult WaitReadable(int fd, int64_t deadline_ns) = 0;
};

/// CLOCK_MONOTONIC, waiting with ppoll(). Stateless.
class MonotonicClock final : public Clock {
 public:
  int64_t NowNs() override;
  WaitResult WaitReadable(int fd, int64_t deadline_ns) override;
};

/// The process's MonotonicClock: what a UdpDevice uses unless given another.
Clock& SystemClock();
}  // namespace udp

/// A snapshot of one side's (or both sides') counters.
struct UdpCounters {
  uint64_t requests = 0;    ///< ReadWrist/ReadGlove calls that sent a request
  uint64_t replies = 0;     ///< valid replies accepted
  uint64_t timeouts = 0;    ///< attempts that ended with no valid reply by their deadline
  uint64_t retries = 0;     ///< extra attempts sent after a timeout
  uint64_t unanswered = 0;  ///< requests that got no valid reply after every attempt
  /// Well-formed replies to another sequence number (late, duplicate, out of order).
  uint64_t stale = 0;
  uint64_t unexpected = 0;  ///< well-formed, right sequence, wrong type or side
  /// Datagrams rejected by Decode, per udp::DecodeStatus (index kOk unused).
  std::array<uint64_t, udp::kDecodeStatuses> malformed{};
  /// ERROR replies to the outstanding request, per udp::ErrorCode.
  std::array<uint64_t, udp::kErrorCodes> errors{};
  uint64_t forces_sent = 0;       ///< one-way WRIST_FORCE / FINGER_FORCE datagrams sent
  uint64_t invalid_commands = 0;  ///< non-finite / negative commands replaced by zero
  /// send()/recv() failures (e.g. ECONNREFUSED: no server listens on the port).
  uint64_t socket_errors = 0;
  uint64_t lost_transitions = 0;  ///< ok → lost
  uint64_t recoveries = 0;        ///< lost → ok

  uint64_t malformed_total() const;
  UdpCounters& operator+=(const UdpCounters& other);
};

class UdpDevice final : public Device {
 public:
  /// Its name in the device registry (udp_driver.cpp) and in device files.
  static constexpr const char* kDriver = "udp";

  /// Resolves and connects one socket per side in `config.sides`. Throws
  /// ConfigFieldError for a `config` DeviceConfig::ValidateOrThrow refuses (a
  /// side without a port: "udp.right.port", with host:port),
  /// std::invalid_argument when its driver is not udp, and std::runtime_error
  /// naming the config file, the key (udp.left / udp.right) and host:port
  /// when the host does not resolve or the socket cannot be opened. Sends
  /// nothing: a server that is not up yet
  /// simply makes the side kNoData, then kLost. `clock` times every wait and
  /// the lost timer; it must outlive the device.
  explicit UdpDevice(const DeviceConfig& config, udp::Clock& clock = udp::SystemClock());
  UdpDevice(const UdpDevice&) = delete;
  UdpDevice& operator=(const UdpDevice&) = delete;

  const DeviceDescription& description() const override { return description_; }
  /// `out.t_ns` is set to `now_ns` (the server's clock is in the reply but is
  /// not comparable); timeouts and lost_after_s run on the device's clock.
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override;
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override;
  /// Stores the command (carried by every later WRIST_REQUEST) and sends it
  /// one-way at once. Returns kLost while the side is lost, else kOk.
  DeviceStatus WriteWristForce(Side side, const Vec3d& command) override;
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>& command) override;

  /// Version 2 only: the server's end's report of the current epoch, once its
  /// controller runs (its device file's servo.passivity).
  bool HasLink() const override { return true; }
  bool LinkPassivity(Side side, LinkEnergy& remote) override;
  void SetLinkEnergy(Side side, const LinkEnergy& local) override;
  void RestartLinkEnergy(Side side) override;

  /// The version `side` speaks: udp::kVersion until a server answers, then
  /// the version it answered in. Until the first valid reply every request
  /// that went unanswered switches the next one between versions 2 and 1,
  /// so an older server (which drops a version it does not know) is found.
  uint16_t ProtocolVersion(Side side) const;

  UdpCounters Counters(Side side) const;
  UdpCounters Counters() const;  ///< both sides summed
  bool Lost(Side side) const;

 private:
  struct AtomicCounters {
    std::atomic<uint64_t> requests{0}, replies{0}, timeouts{0}, retries{0}, unanswered{0}, stale{0},
        unexpected{0}, forces_sent{0}, invalid_commands{0}, socket_errors{0}, lost_transitions{0},
        recoveries{0};
    std::array<std::atomic<uint64_t>, udp::kDecodeStatuses> malformed{};
    std::array<std::atomic<uint64_t>, udp::kErrorCodes> errors{};
  };
  /// Everything one side's thread touches, on its own cache lines.
  struct alignas(64) SideState {
    udp::UniqueFd socket;
    uint32_t sequence = 0;
    int64_t last_valid_ns = 0;  ///< clock_ time of the last valid reply (or of construction)
    std::atomic<bool> lost{false};
    Vec3d wrist_command{};
    std::array<double, kFingers> finger_command{};
    udp::Buffer tx{};
    std::array<uint8_t, udp::kMaxMessageSize + 1>
        rx{};  ///< one spare byte: oversize datagrams show
    udp::Message reply;
    /// The version requests go out in; fixed by the first valid reply.
    std::atomic<uint16_t> version{udp::kVersion};
    bool negotiated = false;
    udp::EnergyReport local;   ///< the loop's end, sent in version 2 (epoch: ours)
    udp::EnergyReport remote;  ///< the server's end, merged from its replies of our epoch
    AtomicCounters counters;
  };
  enum class Wait { kReply, kTimeout, kError };

  /// Sends the request in `s.tx` (`size` bytes) with retries and waits for a
  /// reply of `type` to `sequence`; on kReply it is in `s.reply`.
  Wait Transact(Side side, SideState& s, std::size_t size, uint32_t sequence,
                udp::MessageType type);
  Wait AwaitReply(Side side, SideState& s, uint32_t sequence, udp::MessageType type,
                  int64_t deadline_ns);
  /// Reads and classifies whatever is queued (late replies) without waiting.
  void Drain(Side side, SideState& s);
  /// Classifies one received datagram; true if it is the awaited reply or an ERROR to it.
  bool Accept(Side side, SideState& s, std::size_t size, uint32_t sequence, udp::MessageType type);
  DeviceStatus Outcome(SideState& s, Wait wait);
  /// The next sequence number of a side; 0 is never sent (it means "nothing outstanding").
  static uint32_t NextSequence(SideState& s) {
    return ++s.sequence != 0 ? s.sequence : ++s.sequence;
  }
  void SendOneWay(SideState& s, const udp::Message& message);

  DeviceDescription description_;
  udp::Clock& clock_;
  int64_t lost_after_ns_;
  int64_t timeout_ns_;
  int retries_;
  std::array<SideState, kSides> sides_;
};

}  // namespace haptel::haptics
