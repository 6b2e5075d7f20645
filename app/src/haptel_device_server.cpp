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
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/udp/arm_server.hpp"
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
    "                            [--delay-ms D]\n"
    "  --side left|right  the arm this server serves\n"
    "  --port N           UDP port to serve on (0: any free port; the ready line names it)\n"
    "  --device FILE      device configuration (default config/devices/sim.yaml); its sim\n"
    "                     section shapes the arm, udp.lost_after_s is the client watchdog\n"
    "  --bind ADDR        address to bind (default 127.0.0.1)\n"
    "  --delay-ms D       added delay each way, 0-50 ms (default 0): commands act D ms after\n"
    "                     they arrive, replies carry the arm as it was D ms before\n"
    "Speaks protocol versions 1 and 2; with the device file's servo.passivity on, a version-2\n"
    "client that observes its end gets the arm's end of the two-port passivity controller.\n"
    "Prints 'haptel-device-server: serving <side> arm of '<name>' on <addr>:<port>' when ready;\n"
    "exits 0 on SIGTERM/SIGINT, 2 on bad arguments or configuration, 1 if it cannot bind.\n";

struct Options {
  std::filesystem::path device;
  Side side = Side::kLeft;
  int port = 0;
  std::string bind = "127.0.0.1";
  double delay_ms = 0.0;
};

Options ParseOptions(int argc, char** argv) {
  const Args args(argc, argv, {"device", "side", "port", "bind", "delay-ms"}, {});
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
  if (const auto delay = args.Value("delay-ms")) {
    char* end = nullptr;
    o.delay_ms = std::strtod(delay->c_str(), &end);
    if (end == delay->c_str() || *end != '\0' ||
        !(o.delay_ms >= 0.0 && o.delay_ms <= udp::kMaxDelay_s * 1e3)) {
      throw UsageError("--delay-ms: expected a number of milliseconds from 0 to " +
                       std::to_string(static_cast<int>(udp::kMaxDelay_s * 1e3)) + ", got '" +
                       *delay + "'");
    }
  }
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

std::string Summary(const udp::ServerCounters& c) {
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
  if (c.malformed[static_cast<std::size_t>(udp::DecodeStatus::kBadVersion)] != 0) {
    s += " (bad_version: a peer speaking a protocol version other than " +
         std::to_string(udp::kMinVersion) + "-" + std::to_string(udp::kVersion) + ")";
  }
  s += "; requests by version: v1 " + std::to_string(c.requests_by_version[1]) + ", v2 " +
       std::to_string(c.requests_by_version[2]);
  s += "; passivity (arm's end): " + std::to_string(c.passivity_ticks) + " ticks damped, " +
       std::to_string(c.passivity_dissipated_j * 1e3) + " mJ, largest alpha " +
       std::to_string(c.passivity_max_alpha) + " N*s/m";
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
    udp::ArmServerOptions server_options;
    server_options.lost_after_s = config.udp.lost_after_s;
    server_options.delay_s = options.delay_ms * 1e-3;
    server_options.passivity = config.servo.passivity;
    server_options.limits.max_damping = config.servo.passivity_max_damping;
    server_options.limits.min_speed = config.servo.passivity_min_speed;
    udp::ArmServer server(sim, options.side, socket.get(), server_options,
                          udp::UnitsOf(sim, options.side));
    std::printf("%s: serving %s arm of '%s' on %s\n", kProgram,
                options.side == Side::kLeft ? "left" : "right", config.name.c_str(), bound.c_str());
    std::fflush(stdout);
    // Short waits: the watchdog and the stop flag are checked between.
    while (g_stop == 0) server.Poll(20'000'000);
    server.ZeroForces();
    log::Info(Summary(server.counters()));
    return cli::kExitOk;
  });
}
