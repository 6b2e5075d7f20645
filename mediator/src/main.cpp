// haptel: the operator side. `haptel run` drives one grand-prix lap.
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "haptel/core/json.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/log.hpp"
#include "haptel/haptics/calibration_procedure.hpp"
#include "haptel/mediator/recorder.hpp"
#include "haptel/mediator/session.hpp"
#include "gravity_bench.hpp"
#include "servo_bench.hpp"
#include "physics_bench.hpp"
#include "skip_bench.hpp"
#include "stability_bench.hpp"

namespace {

std::atomic<bool> g_interrupted{false};
void OnSignal(int) { g_interrupted.store(true); }

constexpr const char* kUsage =
    "usage: haptel run [options]         drive one grand-prix lap\n"
    "       haptel calibrate [options]   calibrate a haptic device (--help for options)\n"
    "       haptel bench servo [options] servo loop benchmark (--help for options)\n"
    "       haptel bench gravity [options] gravity compensation benchmark\n"
    "       haptel bench skip [options]  physics CPU per simulated second: no world, hands, sleeping bodies\n"
    "       haptel bench physics [options] work-precision diagram: step x solver iterations x float/double\n"
    "       haptel bench stability [options] physics stress tests: stiffness, mass ratio, squash, grasp\n"
    "\n"
    "haptel run options:\n"
    "  --config FILE        run configuration (default config/haptel.yaml)\n"
    "  --track FILE         track file (overrides the configuration's 'track')\n"
    "  --interface NAME     mediator interface (a file interfaces/NAME.yaml)\n"
    "  --scene FILE         haptic scene for the hands (YAML, or MHaptic .xml)\n"
    "  --vehicle-name NAME  vehicle name in DDS topic names\n"
    "  --domain N           DDS domain id\n"
    "  --database FILE      SQLite file for the results (overrides 'database')\n"
    "  --vehicle-timeout S  no vehicle state for S seconds: vehicle lost\n"
    "  --trace FILE         record the haptic device's readings (for the replay driver)\n"
    "  --json               end with one JSON line of results on stdout\n"
    "  --quiet              no progress lines\n";

std::filesystem::path SelfDirectory() {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path(".") : self.parent_path();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace haptel;
  using namespace haptel::mediator;
  log::SetProgram("haptel");
  // Sub-commands with their own options: each parses argv from its own name on.
  const std::string command = argc > 1 ? argv[1] : "";
  if (command == "calibrate") return haptics::CalibrateMain(argc - 1, argv + 1);
  if (command == "bench") {
    const std::string which = argc > 2 ? argv[2] : "";
    if (which == "servo") return bench::BenchServoMain(argc - 2, argv + 2);
    if (which == "gravity") return bench::BenchGravityMain(argc - 2, argv + 2);
    if (which == "skip") return bench::BenchSkipMain(argc - 2, argv + 2);
    if (which == "physics") return bench::BenchPhysicsMain(argc - 2, argv + 2);
    if (which == "stability") return bench::BenchStabilityMain(argc - 2, argv + 2);
    std::fprintf(stderr, "haptel bench: expected one of: servo, gravity, skip, stability, physics (got '%s')\n", which.c_str());
    return 2;
  }
  SessionSetup setup;
  bool json = false;
  try {
    const Args args(argc, argv, {"config", "track", "interface", "scene", "vehicle-name", "domain", "database", "vehicle-timeout", "trace"},
                    {"json", "quiet", "help"});
    if (args.Flag("help")) {
      std::fputs(kUsage, stdout);
      return 0;
    }
    if (args.positional().size() != 1 || args.positional()[0] != "run") {
      throw UsageError(args.positional().empty() ? "missing command (run)"
                                                 : "unknown command '" + args.positional()[0] + "'");
    }
    json = args.Flag("json");
    setup.progress = !args.Flag("quiet");
    setup.run = LoadRun(args.Value("config").value_or(ShippedFile("config/haptel.yaml").string()));
    if (auto track = args.Value("track")) setup.run.track = *track;
    if (auto name = args.Value("interface")) setup.run.interface = *name;
    if (auto domain = args.Int("domain", 0, 232)) setup.run.link.domain_id = *domain;
    if (auto db = args.Value("database")) setup.run.database = *db;
    if (auto trace = args.Value("trace")) setup.trace = *trace;
    if (auto timeout = args.Value("vehicle-timeout")) {
      char* end = nullptr;
      const double s = std::strtod(timeout->c_str(), &end);
      if (end == timeout->c_str() || *end != '\0' || !(s >= 0.05 && s <= 60.0)) {
        throw UsageError("option --vehicle-timeout: expected seconds in [0.05, 60], got '" + *timeout + "'");
      }
      setup.run.vehicle_timeout_s = s;
    }
    setup.track = LoadTrack(setup.run.track);
    setup.vehicle = LoadVehicle(setup.run.vehicle);
    if (auto name = args.Value("vehicle-name")) setup.vehicle.name = *name;
    const std::filesystem::path interface_file = InterfaceFile(setup.run, setup.run.interface);
    if (InterfaceName(interface_file).rfind("cockpit", 0) == 0) {
      setup.cockpit = LoadCockpit(interface_file);
    } else {
      setup.gesture = LoadGesture(interface_file);
    }
    if (auto scene = args.Value("scene")) setup.run.scene = *scene;
    if (!setup.run.scene.empty()) setup.scene = LoadSceneFile(setup.run.scene);
    if (setup.cockpit || setup.scene) setup.physics = LoadPhysics(setup.run.physics);
    setup.device = LoadDevice(setup.run.device);
    if (setup.device.driver != "sim") {
      throw ConfigError(setup.run.device.string() + ": key 'driver': expected 'sim' for haptel run "
                        "(the automatic operator moves the simulated arms), got '" + setup.device.driver + "'");
    }
    if (!setup.device.calibration.empty()) setup.calibration = LoadCalibration(setup.device.calibration);
    if (!setup.device.gravity.empty()) setup.gravity = LoadGravityGrid(setup.device.gravity);
    setup.vehicle_program = SelfDirectory() / "haptel-vehicle";
  } catch (const UsageError& e) {
    std::fprintf(stderr, "haptel: %s (see haptel --help)\n", e.what());
    return 2;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "haptel: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // anything else while reading the set-up is still bad input
    std::fprintf(stderr, "haptel: configuration: %s\n", e.what());
    return 2;
  }

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  SessionResult result;
  int64_t run_id = 0;
  try {
    result = RunSession(setup, g_interrupted);
    Recorder recorder(setup.run.database);
    run_id = recorder.Save(result.record);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel: %s\n", e.what());
    return 1;
  }

  const RunRecord& r = result.record;
  std::printf("haptel: %s — %s\n", ToString(result.outcome).c_str(), result.message.c_str());
  std::printf("  track %s, interface %s, vehicle %s (pid %d)\n", r.track.c_str(), r.interface.c_str(),
              r.vehicle.c_str(), r.vehicle_pid);
  std::printf("  lap time %.2f s, gates passed %d/%d, missed %d, obstacles touched %d\n", r.lap_time_s,
              r.gates_passed, r.gates_total, r.gates_missed, r.obstacles_touched);
  for (const GateSplit& s : r.splits) {
    if (s.split_s >= 0) std::printf("    gate %d  %7.2f s  %s\n", s.gate + 1, s.split_s, s.passed ? "passed" : "MISSED");
  }
  std::printf("  servo %.1f Hz (p99 period %.0f us, %llu overruns)\n", r.servo_rate_hz, r.servo_period_p99_us,
              static_cast<unsigned long long>(result.servo_overruns));
  if (result.physics_rate_hz > 0) {
    std::printf("  physics %.1f Hz (p99 period %.0f us, longest step %.0f us, %llu hand resets), controls grasped after %.2f s\n",
                result.physics_rate_hz, result.physics_period_p99_us, result.physics_step_max_us,
                static_cast<unsigned long long>(result.physics_hand_resets), result.grasp_s);
  }
  std::printf("  command round trip p50 %.2f ms, p99 %.2f ms\n", r.command_rtt_ms_p50, r.command_rtt_ms_p99);
  std::printf("  video %lld frames, %.1f fps, latency p50 %.1f ms\n", static_cast<long long>(r.video_frames),
              r.video_fps, r.video_latency_ms_p50);
  std::printf("  recorded as run %lld in %s\n", static_cast<long long>(run_id), setup.run.database.c_str());
  if (json) {
    std::ostringstream o;
    o << "{\"completed\":" << (r.completed ? "true" : "false") << ",\"outcome\":" << JsonString(r.outcome)
      << ",\"message\":" << JsonString(result.message) << ",\"lap_time_s\":" << JsonNumber(r.lap_time_s)
      << ",\"gates_passed\":" << r.gates_passed << ",\"gates_total\":" << r.gates_total
      << ",\"gates_missed\":" << r.gates_missed << ",\"obstacles_touched\":" << r.obstacles_touched
      << ",\"vehicle_pid\":" << r.vehicle_pid << ",\"servo_rate_hz\":" << JsonNumber(r.servo_rate_hz)
      << ",\"servo_period_p99_us\":" << JsonNumber(r.servo_period_p99_us)
      << ",\"servo_overruns\":" << result.servo_overruns
      << ",\"command_rtt_ms_p50\":" << JsonNumber(r.command_rtt_ms_p50)
      << ",\"command_rtt_ms_p99\":" << JsonNumber(r.command_rtt_ms_p99) << ",\"video_frames\":" << r.video_frames
      << ",\"video_fps\":" << JsonNumber(r.video_fps) << ",\"video_latency_ms_p50\":" << JsonNumber(r.video_latency_ms_p50)
      << ",\"lost_detect_s\":" << JsonNumber(result.lost_detect_s)
      << ",\"physics_rate_hz\":" << JsonNumber(result.physics_rate_hz)
      << ",\"physics_period_p99_us\":" << JsonNumber(result.physics_period_p99_us)
      << ",\"physics_step_max_us\":" << JsonNumber(result.physics_step_max_us)
      << ",\"physics_hand_resets\":" << result.physics_hand_resets
      << ",\"grasp_s\":" << JsonNumber(result.grasp_s) << ",\"scene_bodies\":" << result.scene_bodies << ",\"interface\":" << JsonString(r.interface)
      << ",\"track\":" << JsonString(r.track) << ",\"run_id\":" << run_id
      << ",\"database\":" << JsonString(setup.run.database.string()) << "}";
    std::printf("%s\n", o.str().c_str());
  }
  std::fflush(stdout);
  switch (result.outcome) {
    case Outcome::kCompleted: return 0;
    case Outcome::kVehicleLost:
    case Outcome::kVehicleDidNotStart: return 3;
    default: return 1;
  }
}
