// haptel-vehicle: one vehicle node. Subscribes to its command topic, drives
// its adapter, publishes state and camera video; stops the motors when
// commands stop coming (watchdog) and on SIGTERM/SIGINT.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>

#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/security.hpp"
#include "haptel/vehicles/vehicle_kinds.hpp"

namespace {
constexpr const char* kUsage =
    "usage: haptel-vehicle [--config FILE] [--track FILE] [--name NAME] [--domain N] [--can "
    "IFACE]\n"
    "                      [--serial-port PATH] [--link-fault SPEC] [--link-profile NAME] "
    "[--security DIR]\n"
    "                      [--dds-interfaces ADDR,...] [--dds-peers ADDR,...] [--discovery-server "
    "ADDR:PORT]\n"
    "  --config FILE  vehicle configuration (default config/vehicles/sim-robot.yaml)\n"
    "  --can IFACE    SocketCAN interface of a can-robot (overrides can.interface)\n"
    "  --serial-port PATH  the servo controller of a servo-blimp (overrides servo.port)\n"
    "  --track FILE   track the simulator drives on, or a blimp's course (overrides the file's "
    "'world')\n"
    "  --name NAME    vehicle name, part of its DDS topic names\n"
    "  --domain N     DDS domain id (overrides link.domain_id)\n"
    "  --link-fault SPEC  inject faults into what this process receives, e.g.\n"
    "                 rate=1Mbit,delay=100ms,jitter=20ms,loss=5% (rate in kbit or Mbit, with\n"
    "                 queue=TIME its drop-tail queue's depth, default 100ms; overrides\n"
    "                 link.fault); with it, SIGUSR1 cuts the link both ways and restores it\n"
    "  --link-profile NAME  a named link (config/links/NAME.yaml: lan, wifi-busy, lte-uplink,\n"
    "                 satellite) or a profile file; --link-fault's keys override the profile's\n"
    "  --security DIR DDS Security with the folder `haptel security init` made (overrides\n"
    "                 link.security); this vehicle is identity vehicle-NAME\n"
    "  --dds-interfaces LIST  the network interfaces (IPv4) DDS may use (overrides "
    "link.interfaces)\n"
    "  --dds-peers LIST       where the operator's host is: unicast discovery (overrides "
    "link.peers)\n"
    "  --discovery-server ADDR:PORT  meet through a Fast DDS discovery server (haptel "
    "discovery-server)\n"
    "  --reality NAME|FILE  a simulated vehicle's hidden truth (config/realities/NAME.yaml: none,\n"
    "                 lab, harsh; or a file; overrides the file's 'reality')\n"
    "  --reality-seed N  the reality's draws (default: the reality file's seed)\n"
    "  --truth FILE   write the truth record here: the drawn reality, then the true pose at\n"
    "                 the control rate (for scoring; the state never says it)\n"
    "  --cameras LIST  which of the file's cameras stream, e.g. pilot or pilot,surveillance\n"
    "                 (a study condition's camera set-up; the driven camera always)\n";
}  // namespace

namespace {

/// What a node counted, for its last line.
std::string Summary(const haptel::vehicles::NodeCounters& c) {
  return std::to_string(c.commands_accepted) + " commands, " +
         std::to_string(c.commands_malformed) + " malformed, " + std::to_string(c.commands_stale) +
         " stale, " +
         (c.commands_refused > 0
              ? std::to_string(c.commands_refused) + " refused (another operator's), "
              : "") +
         std::to_string(c.frames_published) + " frames (" + std::to_string(c.key_frames_sent) +
         " key, " + std::to_string(c.key_frame_requests) + " key frame requests" +
         (c.frames_skipped > 0
              ? ", " + std::to_string(c.frames_skipped) + " skipped to fit the link"
              : "") +
         (c.frames_passed_through > 0 ? ", " + std::to_string(c.frames_passed_through) +
                                            " passed through as the camera made them"
                                      : "") +
         (c.target_kbps > 0 ? ", last asked for " + std::to_string(c.target_kbps) + " kbit/s"
                            : "") +
         (c.video_feedback_refused > 0 ? ", " + std::to_string(c.video_feedback_refused) +
                                             " feedback refused (another operator's)"
                                       : "") +
         "), " + std::to_string(c.grabs_failed) + " camera grabs failed" +
         (c.camera_stalls > 0 ? " (" + std::to_string(c.camera_stalls) + " stalls)" : "") +
         (c.camera_ended ? ", camera file ended" : "") +
         (c.link_queue_dropped > 0 ? ", " + std::to_string(c.link_queue_dropped) + " packets (" +
                                         std::to_string(c.link_queue_dropped_bytes) +
                                         " bytes) dropped by the link's rate queue"
                                   : "");
}

/// Runs a started node until a signal or until it loses its hardware
/// (AdapterFailure), saying each watchdog trip; then stops it. Returns the
/// exit code: 0, or 3 with the loss said.
int RunNode(haptel::vehicles::Node& node, const haptel::VehicleConfig& config,
            const std::atomic<bool>& stop) {
  using namespace haptel;
  uint64_t trips = 0;
  std::string failure;
  bool fault_said = false;
  while (!stop.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    failure = node.AdapterFailure();
    if (!failure.empty()) break;
    if (!fault_said) {
      // The vehicle stopped itself: it stays safe until restarted; its states
      // carry the fault, which ends the operator's run as vehicle lost.
      if (const std::string fault = node.Fault(); !fault.empty()) {
        fault_said = true;
        log::Error("the vehicle stopped itself: " + fault + "; " + node.MadeSafe() +
                   " until it is restarted");
      }
    }
    const auto c = node.Counters();
    if (c.watchdog_trips > trips) {
      trips = c.watchdog_trips;
      log::Warn("watchdog: no command for " + std::to_string(config.watchdog_timeout_s) + " s, " +
                node.MadeSafe());
    }
  }
  node.Stop();
  if (!failure.empty()) {
    log::Error("the vehicle's hardware is lost: " + failure +
               "; stopped (the hardware's own time-out makes it "
               "safe: a servo controller's serial timeout, a motor controller's watchdog)");
    return cli::kExitLost;
  }
  log::Info(std::string("stopped: ") + node.AtRest() + "; " + Summary(node.Counters()));
  return cli::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace haptel;
  log::SetProgram("haptel-vehicle");
  // First: a signal while the files are read still stops the node cleanly.
  const std::atomic<bool>& stop = InstallStopSignals();
  return cli::Main({"haptel-vehicle", kUsage}, argc, argv, [&] {
    VehicleConfig config;
    vehicles::OpenedVehicle vehicle;
    cli::ReadInput([&] {
      const Args args(argc, argv,
                      {"config", "track", "name", "domain", "can", "serial-port", "link-fault",
                       "link-profile", "security", "dds-interfaces", "dds-peers",
                       "discovery-server", "reality", "reality-seed", "truth", "cameras"},
                      {});
      if (!args.positional().empty())
        throw UsageError("unexpected argument '" + args.positional()[0] + "'");
      const std::filesystem::path file =
          args.Value("config").value_or(ShippedFile("config/vehicles/sim-robot.yaml").string());
      config = LoadVehicle(file);
      if (auto name = args.Value("name")) {
        if (const std::string problem = VehicleNameProblem(*name); !problem.empty()) {
          throw UsageError("option --name: expected " + problem);
        }
        config.name = *name;
      }
      if (auto domain = args.Int("domain", 0, 232)) config.link.domain_id = *domain;
      config.link.fault = LinkFaultFromOptions(args.Value("link-profile"), args.Value("link-fault"),
                                               config.link.fault);
      if (auto security = args.Value("security")) config.link.security = *security;
      if (auto list = args.Value("dds-interfaces"))
        config.link.interfaces = ParseAddressOption("dds-interfaces", *list);
      if (auto list = args.Value("dds-peers"))
        config.link.peers = ParseAddressOption("dds-peers", *list);
      if (auto server = args.Value("discovery-server"))
        config.link.discovery_server = ServerOption(*server);
      if (!config.link.security.empty()) {
        config.link.security_identity = link::VehicleIdentity(config.name);
        link::CheckSecurity(config.link.security, config.link.security_identity);
      }
      if (auto list = args.Value("cameras")) {
        std::vector<std::string> names;
        std::stringstream words(*list);
        for (std::string name; std::getline(words, name, ',');) names.push_back(name);
        if (const std::string problem = KeepOnlyCameras(config, names); !problem.empty())
          throw UsageError("option --cameras " + *list + ": " + problem);
      }
      if (auto world = args.Value("track")) config.world = *world;
      if (auto reality = args.Value("reality")) config.reality = RealityFile(*reality);
      if (auto seed = args.Int("reality-seed", 0, 2147483647)) config.reality_seed = *seed;
      if (auto truth = args.Value("truth")) config.truth_file = *truth;
      if (!config.reality.empty() || !config.truth_file.empty()) {
        if (!config.Kind().simulated) {
          throw UsageError(std::string("option --") +
                           (config.reality.empty() ? "truth" : "reality") + ": the vehicle '" +
                           file.string() + "' is of kind " + config.kind +
                           ", not simulated: its reality and truth are the world's");
        }
        config.ValidateOrThrow();
      }
      if (auto can = args.Value("can")) {
        if (!config.Kind().Uses(kCanSection)) {
          throw UsageError("option --can: the vehicle '" + file.string() + "' is of kind " +
                           config.kind + ", not on a CAN bus");
        }
        config.can.interface = *can;
        config.ValidateOrThrow();
      }
      if (auto port = args.Value("serial-port")) {
        if (!config.Kind().Uses(kServoSection)) {
          throw UsageError("option --serial-port: the vehicle '" + file.string() + "' is of kind " +
                           config.kind + ", not behind a servo controller");
        }
        config.servo.port = *port;
        config.ValidateOrThrow();
      }
      // The world, then the hardware, then the camera: a bus or port that
      // cannot open stops here (exit 2), before any DDS participant exists.
      vehicle = vehicles::OpenVehicle(config, file.string());
    });

    if (config.link.fault.enabled) {
      link::InstallLinkDownSignal();
      log::Info("link faults on what this vehicle receives: " + LinkFaultText(config.link.fault) +
                " (SIGUSR1 cuts the link and restores it)");
    }
    const std::unique_ptr<vehicles::Node> node = vehicle.make_node();
    node->Start();
    log::Info("vehicle '" + config.name + "' (" + config.kind + ") up on domain " +
              std::to_string(config.link.domain_id) + ", " + vehicle.description);
    return RunNode(*node, config, stop);
  });
}
