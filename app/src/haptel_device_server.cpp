// haptel-device-server: serves one arm of a simulated exoskeleton over the
// UDP device protocol (haptics/udp/PROTOCOL.md), as each arm of the original
// device was served by its own computer. Run one per arm; the `udp` device
// driver (UdpDevice) talks to them.
//
// The sim arm integrates in real time: every WRIST_REQUEST steps it to now.
// Nobody holds the arm (no simulated operator), so it settles under its own
// unbalanced weight and moves only under the forces it is commanded.
// One client at a time holds the arm; its forces are zeroed and the arm freed
// for another client when it has been silent for udp.lost_after_s.
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "haptel/config/paths.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/udp/udp_device.hpp"
#include "haptel/udp/udp_protocol.hpp"

namespace {

using namespace haptel;
using namespace haptel::haptics;

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

constexpr const char* kProgram = "haptel-device-server";
constexpr const char* kUsage =
    "usage: haptel-device-server --side left|right --port N [--device FILE] [--bind ADDR]\n"
    "  --side left|right  the arm this server serves\n"
    "  --port N           UDP port to serve on (0: any free port; the ready line names it)\n"
    "  --device FILE      device configuration (default config/devices/sim.yaml); its sim\n"
    "                     section shapes the arm, udp.lost_after_s is the client watchdog\n"
    "  --bind ADDR        address to bind (default 127.0.0.1)\n"
    "Prints 'haptel-device-server: serving <side> arm of '<name>' on <addr>:<port>' when ready;\n"
    "exits 0 on SIGTERM/SIGINT, 2 on bad arguments or configuration, 1 if it cannot bind.\n";

struct Options {
  std::filesystem::path device;
  Side side = Side::kLeft;
  int port = 0;
  std::string bind = "127.0.0.1";
};

struct Peer {
  sockaddr_storage addr{};
  socklen_t len = 0;
  bool Same(const sockaddr_storage& a, socklen_t l) const {
    return l == len && std::memcmp(&a, &addr, len) == 0;
  }
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
  std::array<uint64_t, udp::kDecodeStatuses> malformed{};
};

/// Serves one arm of `sim` on a bound socket. Single-threaded; allocates nothing per datagram.
class ArmServer {
 public:
  ArmServer(SimDevice& sim, Side side, int fd, double session_timeout_s)
      : sim_(sim), side_(side), fd_(fd), session_timeout_ns_(SToNs(session_timeout_s)) {}

  void Serve() {
    while (g_stop == 0) {
      CheckWatchdog();
      pollfd p{fd_, POLLIN, 0};
      const int ready =
          ::poll(&p, 1, 20);  // short: the watchdog and the stop flag are checked between
      if (ready <= 0) continue;
      for (;;) {
        from_len_ = sizeof from_;
        const ssize_t n = ::recvfrom(fd_, rx_.data(), rx_.size(), MSG_DONTWAIT,
                                     reinterpret_cast<sockaddr*>(&from_), &from_len_);
        if (n < 0) break;
        Handle(static_cast<std::size_t>(n));
      }
    }
    ZeroForces();
  }

  const ServerCounters& counters() const { return c_; }

 private:
  void Handle(std::size_t size) {
    ++c_.datagrams;
    const udp::DecodeStatus status = udp::Decode(std::span<const uint8_t>(rx_.data(), size), msg_);
    if (status != udp::DecodeStatus::kOk) {
      ++c_.malformed[static_cast<std::size_t>(status)];
      // A sound header with a type we do not know: say so, so a newer client sees why.
      if (status == udp::DecodeStatus::kUnknownType)
        Reply(udp::ErrorReply{udp::ErrorCode::kUnsupported});
      return;  // anything else is not trusted enough to answer
    }
    const udp::MessageType type = msg_.type();
    const bool request =
        type == udp::MessageType::kWristRequest || type == udp::MessageType::kGloveRequest;
    const bool command =
        type == udp::MessageType::kWristForce || type == udp::MessageType::kFingerForce;
    if (!request && !command) {
      ++c_.unexpected;
      return;
    }
    if (msg_.side != side_) {
      ++c_.wrong_side;
      if (request) Reply(udp::ErrorReply{udp::ErrorCode::kWrongSide});
      return;
    }
    CheckWatchdog();  // a client quiet for too long loses the arm (forces zeroed) before anyone
                      // takes over
    if (session_ && !peer_.Same(from_, from_len_)) {
      ++c_.busy;
      if (request) Reply(udp::ErrorReply{udp::ErrorCode::kBusy});
      return;
    }
    const int64_t now = MonotonicNs();
    if (!session_) {
      session_ = true;
      peer_.addr = from_;
      peer_.len = from_len_;
      has_wrist_seq_ = has_finger_seq_ = false;
    }
    last_heard_ns_ = now;
    if (const auto* p = std::get_if<udp::WristRequest>(&msg_.payload)) {
      ++c_.wrist_requests;
      const udp::WristRequest commands = *p;  // msg_ is reused by Reply
      ApplyWrist(commands.wrist_force);
      ApplyFingers(commands.finger_forces);
      WristRaw raw;
      if (sim_.ReadWrist(side_, now, raw) != DeviceStatus::kOk) {
        ++c_.device_lost;
        Reply(udp::ErrorReply{udp::ErrorCode::kDeviceLost});
        return;
      }
      Reply(udp::WristReply{MonotonicNs(), raw.position, raw.orientation});
    } else if (std::holds_alternative<udp::GloveRequest>(msg_.payload)) {
      ++c_.glove_requests;
      GloveRaw raw;
      if (sim_.ReadGlove(side_, now, raw) != DeviceStatus::kOk) {
        ++c_.device_lost;
        Reply(udp::ErrorReply{udp::ErrorCode::kDeviceLost});
        return;
      }
      Reply(udp::GloveReply{MonotonicNs(), raw.sensors, raw.grasp});
    } else if (const auto* w = std::get_if<udp::WristForce>(&msg_.payload)) {
      ApplyWrist(w->command);
    } else if (const auto* f = std::get_if<udp::FingerForce>(&msg_.payload)) {
      ApplyFingers(f->command);
    }
  }

  /// Applies a wrist command unless a newer one (by sequence) was applied already.
  void ApplyWrist(const Vec3d& command) {
    if (has_wrist_seq_ && !udp::SequenceAfter(msg_.sequence, wrist_seq_) &&
        msg_.sequence != wrist_seq_) {
      ++c_.stale_commands;
      return;
    }
    has_wrist_seq_ = true;
    wrist_seq_ = msg_.sequence;
    sim_.WriteWristForce(side_, command);
    ++c_.forces_applied;
  }
  void ApplyFingers(const std::array<double, kFingers>& command) {
    if (has_finger_seq_ && !udp::SequenceAfter(msg_.sequence, finger_seq_) &&
        msg_.sequence != finger_seq_) {
      ++c_.stale_commands;
      return;
    }
    has_finger_seq_ = true;
    finger_seq_ = msg_.sequence;
    sim_.WriteFingerForces(side_, command);
    ++c_.forces_applied;
  }

  /// Answers the datagram in msg_/from_ with `payload`, echoing its sequence and side.
  void Reply(const udp::Payload& payload) {
    const udp::Message reply{msg_.sequence, msg_.side, payload};
    const std::size_t size = udp::Encode(reply, tx_);
    if (size == 0 || ::sendto(fd_, tx_.data(), size, 0, reinterpret_cast<const sockaddr*>(&from_),
                              from_len_) < 0) {
      ++c_.send_errors;
    }
  }

  void CheckWatchdog() {
    if (session_ && MonotonicNs() - last_heard_ns_ >= session_timeout_ns_) {
      ZeroForces();
      session_ = false;
      ++c_.watchdog_trips;
    }
  }

  void ZeroForces() {
    sim_.WriteWristForce(side_, Vec3d{});
    sim_.WriteFingerForces(side_, std::array<double, kFingers>{});
  }

  SimDevice& sim_;
  Side side_;
  int fd_;
  int64_t session_timeout_ns_;
  bool session_ = false;
  Peer peer_;
  int64_t last_heard_ns_ = 0;
  bool has_wrist_seq_ = false;
  bool has_finger_seq_ = false;
  uint32_t wrist_seq_ = 0;
  uint32_t finger_seq_ = 0;
  sockaddr_storage from_{};
  socklen_t from_len_ = 0;
  std::array<uint8_t, udp::kMaxMessageSize + 1> rx_{};
  udp::Buffer tx_{};
  udp::Message msg_;
  ServerCounters c_;
};

Options ParseOptions(int argc, char** argv) {
  const Args args(argc, argv, {"device", "side", "port", "bind"}, {});
  Options o;
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional()[0] + "'");
  const auto side = args.Value("side");
  if (!side) throw UsageError("--side left|right is required");
  if (*side == "left") {
    o.side = Side::kLeft;
  } else if (*side == "right") {
    o.side = Side::kRight;
  } else {
    throw UsageError("--side: expected 'left' or 'right', got '" + *side + "'");
  }
  const auto port = args.Int("port", 0, 65535);
  if (!port) throw UsageError("--port N is required (0: any free port)");
  o.port = *port;
  o.bind = args.Value("bind").value_or(o.bind);
  o.device = args.Value("device").value_or(ShippedFile("config/devices/sim.yaml").string());
  return o;
}

/// Binds a UDP socket to bind:port; returns it and the "addr:port" it is bound to.
udp::UniqueFd Bind(const Options& o, std::string& bound) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(o.port);
  const int rc = getaddrinfo(o.bind.c_str(), service.c_str(), &hints, &found);
  if (rc != 0) throw UsageError("--bind: cannot resolve '" + o.bind + "': " + gai_strerror(rc));
  const std::unique_ptr<addrinfo, decltype(&freeaddrinfo)> list(found, &freeaddrinfo);
  std::string error = "no address";
  for (const addrinfo* a = list.get(); a != nullptr; a = a->ai_next) {
    udp::UniqueFd fd(::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol));
    if (fd.get() < 0 || ::bind(fd.get(), a->ai_addr, a->ai_addrlen) != 0) {
      error = std::strerror(errno);
      continue;
    }
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    char host[NI_MAXHOST];
    char port[NI_MAXSERV];
    if (::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&addr), &len) != 0 ||
        getnameinfo(reinterpret_cast<sockaddr*>(&addr), len, host, sizeof host, port, sizeof port,
                    NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
      error = "cannot read the bound address";
      continue;
    }
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + string.
    bound.clear();
    if (addr.ss_family == AF_INET6) bound += '[';
    bound += host;
    if (addr.ss_family == AF_INET6) bound += ']';
    bound.append(":").append(port);
    return fd;
  }
  throw std::runtime_error("cannot bind " + o.bind + ":" + service + ": " + error);
}

std::string Summary(const ServerCounters& c) {
  std::string s =
      "stopped: " + std::to_string(c.datagrams) + " datagrams, " +
      std::to_string(c.wrist_requests) + " wrist and " + std::to_string(c.glove_requests) +
      " glove requests, " + std::to_string(c.forces_applied) + " commands applied, " +
      std::to_string(c.stale_commands) + " stale, " + std::to_string(c.busy) + " busy, " +
      std::to_string(c.wrong_side) + " wrong side, " + std::to_string(c.unexpected) +
      " unexpected, " + std::to_string(c.watchdog_trips) + " watchdog trips; malformed:";
  uint64_t total = 0;
  for (int i = 1; i < udp::kDecodeStatuses; ++i) {
    if (c.malformed[i] == 0) continue;
    total += c.malformed[i];
    s.append(" ").append(udp::ToString(static_cast<udp::DecodeStatus>(i))).append("=");
    s.append(std::to_string(c.malformed[i]));
  }
  if (total == 0) s += " none";
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  log::SetProgram(kProgram);
  return cli::Main({kProgram, kUsage}, argc, argv, [&] {
    Options options;
    DeviceConfig config;
    cli::ReadInput([&] {
      options = ParseOptions(argc, argv);
      config = LoadDevice(options.device);
      if (!config.sides[Index(options.side)]) {
        throw ConfigError(options.device.string() + ": key 'sides': expected the " +
                          (options.side == Side::kLeft ? "left" : "right") +
                          " arm this server was asked to serve");
      }
    });
    std::string bound;
    const udp::UniqueFd socket = Bind(options, bound);  // a port in use: exit 1

    // No SA_RESTART: the signal must wake the server from its blocking receive.
    struct sigaction action {};
    action.sa_handler = OnSignal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGTERM, &action, nullptr);
    sigaction(SIGINT, &action, nullptr);
    SimDevice sim(config, OperatorConfig{});
    ArmServer server(sim, options.side, socket.get(), config.udp.lost_after_s);
    std::printf("%s: serving %s arm of '%s' on %s\n", kProgram,
                options.side == Side::kLeft ? "left" : "right", config.name.c_str(), bound.c_str());
    std::fflush(stdout);
    server.Serve();
    log::Info(Summary(server.counters()));
    return cli::kExitOk;
  });
}
