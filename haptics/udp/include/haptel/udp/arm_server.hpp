#pragma once
/// @file One arm of a simulated exoskeleton served over the UDP device
/// protocol (haptics/udp/PROTOCOL.md): the server side of `haptel-device-server`,
/// in the library so that a benchmark or a test can run it in process.
///
/// One client at a time holds the arm; its forces are zeroed and the arm
/// freed for another client when it has been silent for `lost_after_s`. A
/// request is answered in the version it came in (1 or 2).
///
/// Added delay (`delay_s`, the bench's 1–5 ms each way): a command takes
/// effect `delay_s` after it arrived, and a WRIST_REPLY carries the reading
/// the arm had `delay_s` before (with the energy report of that moment), so a
/// synchronous client sees a delayed channel without waiting for it.
///
/// Two-port passivity (twoport.hpp), the arm's end: with `passivity` on (the
/// device file's servo.passivity) and a version-2 client that reports its
/// own end, the server observes the arm's port — the force it holds against
/// the arm's motion, in SI through the arm's calibration — and damps the arm
/// when what left the channel here exceeds what the client's end put in
/// (its E_in less what it charged), each report as it arrived, delayed with
/// its command. Its report (E_in, dissipated, ticks, largest α) goes back
/// in every WRIST_REPLY. The client owns the epoch: a new one restarts this
/// end.
///
/// Single-threaded; allocates nothing per datagram. Time comes from a
/// udp::Clock, so a benchmark can step the arm in simulated time.
#include <sys/socket.h>

#include <array>
#include <cstdint>

#include "haptel/haptics/sim_device.hpp"
#include "haptel/haptics/twoport.hpp"
#include "haptel/udp/udp_device.hpp"
#include "haptel/udp/udp_protocol.hpp"

namespace haptel::haptics::udp {

/// What the server knows of its arm, to observe its port in SI: a sim arm's
/// hidden truth, a real arm's calibration.
struct ArmUnits {
  Vec3d tracker_scale{1.0, 1.0, 1.0};  ///< metres = scale · raw + offset
  Vec3d tracker_offset{};
  Vec3d force_slope{1.0, 1.0, 1.0};  ///< newtons = slope · command
  double force_limit_n = 1e9;        ///< the arm saturates here (vector norm), N
};
/// A sim arm's truth as ArmUnits.
ArmUnits UnitsOf(const SimDevice& sim, Side side);

struct ArmServerOptions {
  double lost_after_s = 0.1;  ///< the client watchdog (udp.lost_after_s)
  double delay_s = 0.0;       ///< added each way; at most kMaxDelay_s
  bool passivity = false;     ///< run the arm's end of the two-port (servo.passivity)
  TwoPortLimits limits;       ///< its cap and speed floor (servo.passivity_*)
};

struct ServerCounters {
  uint64_t datagrams = 0;
  uint64_t wrist_requests = 0;
  uint64_t glove_requests = 0;
  uint64_t forces_applied = 0;
  uint64_t stale_commands = 0;  ///< force commands older than one already applied (not applied)
  uint64_t unexpected = 0;      ///< replies sent to the server
  uint64_t busy = 0;            ///< datagrams from a second client while one holds the arm
  uint64_t wrong_side = 0;
  uint64_t device_lost = 0;
  uint64_t watchdog_trips = 0;  ///< client silent: forces zeroed, arm freed
  uint64_t send_errors = 0;
  uint64_t delay_overflows = 0;  ///< commands dropped: the delay queue was full
  std::array<uint64_t, kDecodeStatuses> malformed{};
  std::array<uint64_t, kVersion + 1> requests_by_version{};  ///< index: protocol version
  // The arm's end of the two-port.
  uint64_t passivity_ticks = 0;         ///< services that damped the arm
  double passivity_dissipated_j = 0.0;  ///< J its damping did on the arm (all epochs)
  double passivity_max_alpha = 0.0;     ///< N·s/m
  uint64_t epochs = 0;                  ///< restarts of the two-port (the client's new epochs)
};

/// The longest added delay (the reading ring and command queue are sized for it at 1 kHz).
inline constexpr double kMaxDelay_s = 0.05;

class ArmServer {
 public:
  /// `arm` and `clock` must outlive the server; `fd` is a bound UDP socket;
  /// `units` turn the arm's raw readings and commands into metres and newtons.
  ArmServer(Device& arm, Side side, int fd, const ArmServerOptions& options, const ArmUnits& units,
            Clock& clock = SystemClock());

  /// Waits up to `wait_ns` for a datagram, then handles every one queued.
  void Poll(int64_t wait_ns);
  /// Forces to zero (at stop).
  void ZeroForces();

  const ServerCounters& counters() const { return c_; }
  /// The arm's end (for tests and the bench).
  const TwoPortPassivity& arm_end() const { return arm_end_; }
  /// The command the arm holds now, the controller's damping included (device units).
  const Vec3d& applied() const { return written_; }

 private:
  struct Reading {
    int64_t t_ns = 0;
    WristRaw raw{};
    EnergyReport report;  ///< this end's, at the reading
  };
  struct Command {
    int64_t due_ns = 0;
    Vec3d command{};
    EnergyReport report;  ///< the client's, as it came with the command
  };
  static constexpr std::size_t kRing = 128;

  void Handle(std::size_t size);
  /// Queues a wrist command (unless older than one applied) to act delay_s from now.
  /// False when it was stale or the queue full (counted).
  bool QueueWrist(const Vec3d& command, const EnergyReport* report, int64_t now);
  void ApplyFingers(const std::array<double, kFingers>& command);
  /// Steps the arm to `now`, observes its port, applies what is due (with
  /// the controller's damping). False when the arm did not answer.
  bool Service(int64_t now);
  void Reply(const Payload& payload);
  void CheckWatchdog();
  void StartSession();
  EnergyReport OwnReport() const;
  Vec3d Metres(const Vec3d& raw) const;
  Vec3d Newtons(const Vec3d& command) const;

  Device& sim_;
  ArmUnits units_;
  Side side_;
  int fd_;
  ArmServerOptions options_;
  Clock& clock_;
  int64_t session_timeout_ns_;
  int64_t delay_ns_;
  bool session_ = false;
  sockaddr_storage peer_{};
  socklen_t peer_len_ = 0;
  int64_t last_heard_ns_ = 0;
  bool has_wrist_seq_ = false;
  bool has_finger_seq_ = false;
  uint32_t wrist_seq_ = 0;
  uint32_t finger_seq_ = 0;
  sockaddr_storage from_{};
  socklen_t from_len_ = 0;
  std::array<uint8_t, kMaxMessageSize + 1> rx_{};
  Buffer tx_{};
  Message msg_;
  ServerCounters c_;

  // The arm's channel: readings (newest last) and commands in flight.
  std::array<Reading, kRing> readings_{};
  uint64_t reads_ = 0;
  std::array<Command, kRing> queue_{};
  uint64_t queued_ = 0, applied_ = 0;  ///< queue_ is a ring: [applied_, queued_)
  Vec3d command_{};                    ///< the client's command in force (device units)
  Vec3d written_{};                    ///< what the arm holds: command_ plus the damping
  // The arm's end of the two-port.
  TwoPortPassivity arm_end_;
  EnergyReport remote_;  ///< the client's, merged as its commands took effect
  bool remote_seen_ = false;
  Vec3d position_{};  ///< m, the arm at the last service
  Vec3d velocity_{};  ///< m/s, low-pass filtered
  int64_t last_service_ns_ = 0;
  int64_t last_request_ns_ = 0;
  double period_s_ = 0.001;  ///< the client's tick, from its requests
  uint64_t acted_ticks_ = 0;
  bool acted_this_tick_ = false;
  double max_alpha_ = 0.0;
  double dissipated_before_ = 0.0;  ///< J, earlier epochs
};

}  // namespace haptel::haptics::udp
