// `haptel run`: one lap from the command line.
#include "haptel/mediator/run_setup.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>

#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/security.hpp"
#include "haptel/mediator/controller_errors.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/run_counters.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/record/run_picture.hpp"
#include "haptel/record/unsaved_run.hpp"
#include "haptel/view/view.hpp"
#include "simulated_time.hpp"

namespace haptel::mediator {
namespace {

constexpr const char* kRunUsage =
    "usage: haptel run [options]   drive one grand-prix lap\n"
    "\n"
    "options:\n"
    "  --config FILE        run configuration (default config/haptel.yaml)\n"
    "  --track FILE         track file (overrides the configuration's 'track')\n"
    "  --interface NAME     mediator interface to start with (a file interfaces/NAME.yaml);\n"
    "                       F1-F6 switch between the run configuration's 'switchable_interfaces';\n"
    "                       a blimp: blimp-gesture (a haptic device's two arms), blimp-keys\n"
    "                       (the default for a person at the simulated device) or blimp-gamepad\n"
    "  --operator KIND      auto (the simulated driver; default without a display) or person\n"
    "  --device FILE        haptic device file: sim, udp (haptel-device-server arms) or replay\n"
    "  --trace-in FILE      the trace a replay device plays (overrides its 'replay.trace')\n"
    "  --time-limit S       end the run after S seconds, outcome 'time limit' (person: 600)\n"
    "  --lap-limit S        end the run when the lap's clock (from the start line) passes S,\n"
    "                       outcome 'time limit'; before the line the approach counts (a\n"
    "                       study's trial cap: every interface gets the same lap time)\n"
    "  --predict on|off     the predictive display (default off): the operator sees the vehicle\n"
    "                       where its model says it is now, from the delayed states and the\n"
    "                       commands sent since; the model's error is reported either way\n"
    "  --view KIND          window (default with a display) or none\n"
    "  --third-person       beside the camera's picture, a chase camera's view of the robot on\n"
    "                       its track (a simulated robot only: its track is known here)\n"
    "  --record FILE.mp4    record the operator's view as H.264 MP4 (offscreen without a window)\n"
    "  --scene FILE         haptic scene for the hands (YAML, or the thesis's MHaptic .xml),\n"
    "                       moved by the configuration's scene_placement\n"
    "  --vehicle FILE       vehicle configuration the spawned vehicle runs (overrides 'vehicle'),\n"
    "                       e.g. config/vehicles/can-robot-sim.yaml (the CAN code path)\n"
    "  --vehicle-name NAME  vehicle name in DDS topic names\n"
    "  --attach             spawn no vehicle: drive the one already running under that name\n"
    "                       on the domain (a haptel-vehicle started by hand, here or on\n"
    "                       another host); --vehicle still says what kind it is\n"
    "  --domain N           DDS domain id\n"
    "  --link-fault SPEC    inject faults into what both processes receive, e.g.\n"
    "                       rate=1Mbit,delay=100ms,jitter=20ms,loss=5% (rate in kbit or Mbit,\n"
    "                       with queue=TIME its drop-tail queue's depth, default 100ms;\n"
    "                       overrides link.fault; the spawned vehicle gets it too); with it,\n"
    "                       SIGUSR1 cuts the link both ways\n"
    "  --link-profile NAME  a named link (config/links/NAME.yaml: lan, wifi-busy, lte-uplink,\n"
    "                       satellite) or a profile file; the keys --link-fault names override\n"
    "                       the profile's (--link-profile lte-uplink --link-fault loss=5%)\n"
    "  --security DIR       DDS Security with the folder `haptel security init DIR` made\n"
    "                       (overrides link.security; the spawned vehicle gets it too)\n"
    "  --dds-interfaces LIST  network interfaces (IPv4, comma-separated) DDS may use\n"
    "                       (overrides link.interfaces; the spawned vehicle keeps its own)\n"
    "  --dds-peers LIST     the vehicles' hosts, for unicast discovery (overrides link.peers)\n"
    "  --discovery-server ADDR:PORT  meet the vehicle through a Fast DDS discovery server\n"
    "                       (haptel discovery-server; the spawned vehicle uses it too)\n"
    "  --insecure           say nothing of a link beyond this host without --security (a\n"
    "                       vehicle's owner is then bound to DDS's writer identity: proof\n"
    "                       against mistakes, not attackers)\n"
    "  --database FILE      SQLite file for the results (overrides 'database')\n"
    "  --vehicle-timeout S  no vehicle state for S seconds: vehicle lost\n"
    "  --trace FILE         record the haptic device's readings (for the replay driver)\n"
    "  --fleet FILE         one operator, several vehicles (config/fleets/*.yaml): each vehicle\n"
    "                       spawned or attached as the file says, driven one at a time, the\n"
    "                       others held safe; one row per vehicle in the database. The automatic\n"
    "                       operator by default; with --operator person the keys (or controller)\n"
    "                       drive the vehicle driven, Tab/1-9 turn to another, each vehicle with\n"
    "                       its kind's interface (the fleet file's 'interface', else keyboard /\n"
    "                       blimp-keys at the simulated device)\n"
    "  --simulated-time     every part on one simulated clock in this one process, as fast as\n"
    "                       the CPU allows: the servo ticks, the physics, the simulated robot\n"
    "                       (stepped here, no DDS; commands and states delayed by the link\n"
    "                       fault's delay), the automatic operator; the same seed gives the\n"
    "                       same lap to the tick. Needs --operator auto, a vehicle whose kind\n"
    "                       steps in process (sim-robot) and no view; the JSON's speedup is\n"
    "                       simulated seconds per wall-clock second\n"
    "  --json               end with one JSON line of results on stdout\n"
    "  --quiet              no progress lines\n";

/// [{"t_s":…,"from":…,"to":…}, …]
std::string SwitchesJson(const std::vector<haptel::record::SwitchRecord>& switches) {
  std::string out = "[";
  for (const auto& s : switches) {
    if (out.size() > 1) out += ",";
    out += "{\"t_s\":" + haptel::JsonNumber(s.t_s) + ",\"from\":" + haptel::JsonString(s.from) +
           ",\"to\":" + haptel::JsonString(s.to) + "}";
  }
  return out + "]";
}

/// {"path":…,"frames":…,"frames_lost":…[,"error":…]}, or null without a log.
std::string CanLogJson(const haptel::mediator::CanLogReport& log) {
  if (log.path.empty()) return "null";
  std::string out = "{\"path\":" + haptel::JsonString(log.path) +
                    ",\"frames\":" + std::to_string(log.frames) +
                    ",\"frames_lost\":" + std::to_string(log.frames_lost);
  if (!log.error.empty()) out += ",\"error\":" + haptel::JsonString(log.error);
  return out + "}";
}

/// {"name":n,...}
std::string CountersJson(const std::vector<haptel::record::RunCounter>& counters) {
  std::string out = "{";
  for (const auto& c : counters) {
    if (out.size() > 1) out += ",";
    out += haptel::JsonString(c.name) + ":" + std::to_string(c.value);
  }
  return out + "}";
}

/// ["name",...]
std::string NamesJson(const std::vector<std::string>& names) {
  std::string out = "[";
  for (const std::string& name : names) {
    if (out.size() > 1) out += ",";
    out += haptel::JsonString(name);
  }
  return out + "]";
}

/// Whether the run's vehicle has a servo controller that reports errors (a Maestro).
bool ReportsControllerErrors(const haptel::mediator::SessionSetup& setup) {
  const haptel::VehicleKindInfo* kind = haptel::FindVehicleKind(setup.vehicle.kind);
  return kind != nullptr && kind->Uses(haptel::kServoSection) &&
         setup.vehicle.servo.protocol == haptel::ServoProtocol::kMaestro;
}

}  // namespace

Args ParseRunArgs(int argc, const char* const* argv) {
  return Args(argc, argv, {"config",       "track",          "interface",  "scene",
                           "vehicle-name", "domain",         "database",   "vehicle-timeout",
                           "trace",        "operator",       "device",     "trace-in",
                           "time-limit",   "lap-limit",      "view",       "record",
                           "vehicle",      "predict",        "link-fault", "link-profile",
                           "security",     "dds-interfaces", "dds-peers",  "discovery-server",
                           "fleet"},
              {"json", "quiet", "attach", "third-person", "simulated-time", "insecure"});
}

namespace {

/// A gate whose opening (between the posts' surfaces) is narrower than the
/// robot can never be passed: the lap would run to its cap. Refused before
/// anything runs, naming the gate and both widths.
void CheckGatesFit(const TrackConfig& track, const VehicleConfig& vehicle) {
  const double across = 2.0 * vehicle.body.radius;
  const Track placed(track);
  for (size_t i = 0; i < track.gates.size(); ++i) {
    const GateSpec& gate = track.gates[i];
    const double opening = gate.width - 2.0 * track.post_radius;
    // An obstacle in the opening (a post in the gate) leaves what is beside it.
    std::vector<size_t> blocking;
    if (const double free = GateFreeWidth(placed, i, &blocking);
        opening >= across && !blocking.empty() && free <= across) {
      std::string names;
      for (size_t k : blocking) {
        char one[160];
        std::snprintf(one, sizeof one, "%sobstacles[%zu] (radius %.3f m at [%.2f, %.2f])",
                      names.empty() ? "" : ", ", k, track.obstacles[k].radius,
                      track.obstacles[k].center.x(), track.obstacles[k].center.y());
        names += one;
      }
      char text[600];
      std::snprintf(text, sizeof text,
                    ": key 'gates[%zu]': the gate at %.2f m is blocked by %s: its widest free gap "
                    "is %.3f m, not "
                    "wider than vehicle '%s' (%.3f m across, body.radius in %s); expected the "
                    "obstacle out of the "
                    "gate's opening, or a gap wider than %.3f m",
                    i, gate.along, names.c_str(), free, vehicle.name.c_str(), across,
                    vehicle.file.string().c_str(), across);
      throw ConfigError(track.file.string() + text);
    }
    if (opening >= across) continue;
    char text[400];
    std::snprintf(
        text, sizeof text,
        ": key 'gates[%zu]': the gate at %.2f m is %.3f m between its posts' surfaces (width %.3f "
        "m "
        "less two posts of radius %.3f m), narrower than vehicle '%s' (%.3f m across, body.radius "
        "in %s); expected a width of at least %.3f m",
        i, gate.along, opening, gate.width, track.post_radius, vehicle.name.c_str(), across,
        vehicle.file.string().c_str(), across + 2.0 * track.post_radius);
    throw ConfigError(track.file.string() + text);
  }
}

}  // namespace

namespace {

/// What the command line says of who drives and what is shown.
struct Operation {
  bool person = false;   ///< a person drives (else the automatic operator)
  bool display = false;  ///< there is a display to open a window on
};

/// The run's configuration and the options that override it: the files,
/// the link, the database, the trace.
void ReadRunOptions(const Args& args, SessionSetup& setup) {
  setup.progress = !args.Flag("quiet");
  setup.attach = args.Flag("attach");
  setup.run = LoadRun(args.Value("config").value_or(ShippedFile("config/haptel.yaml").string()));
  if (auto track = args.Value("track")) setup.run.track = *track;
  if (auto name = args.Value("interface")) setup.run.interface = *name;
  if (auto domain = args.Int("domain", 0, 232)) setup.run.link.domain_id = *domain;
  setup.run.link.fault = LinkFaultFromOptions(args.Value("link-profile"), args.Value("link-fault"),
                                              setup.run.link.fault);
  if (auto predict = args.Value("predict")) {
    if (*predict != "on" && *predict != "off")
      throw UsageError("option --predict: expected on or off, got '" + *predict + "'");
    setup.predict = *predict == "on";
  }
  if (auto security = args.Value("security")) setup.run.link.security = *security;
  if (auto list = args.Value("dds-interfaces"))
    setup.run.link.interfaces = ParseAddressOption("dds-interfaces", *list);
  if (auto list = args.Value("dds-peers"))
    setup.run.link.peers = ParseAddressOption("dds-peers", *list);
  if (auto server = args.Value("discovery-server"))
    setup.run.link.discovery_server = ServerOption(*server);
  // Before anything is spawned: a missing identity or an expired certificate is one line.
  if (!setup.run.link.security.empty())
    link::CheckSecurity(setup.run.link.security, link::OperatorIdentity());
  // Each file option before anything opens it: a FIFO would be waited on for ever, deaf to signals.
  if (auto db = args.Value("database")) {
    CheckFileOption("database", *db, "an SQLite file (new or a Haptel database)");
    setup.run.database = *db;
  }
  if (auto trace = args.Value("trace")) {
    CheckFileOption("trace", *trace, "a file name for the device's trace, such as arms.trace");
    setup.trace = *trace;
  }
  if (auto s = args.Number("vehicle-timeout", 0.05, 60.0)) setup.run.vehicle_timeout_s = *s;
}

/// Who drives (--operator), what they see (--view, --record) and for how long.
Operation ReadOperation(const Args& args, SessionSetup& setup) {
  Operation op;
  op.display = view::View::DisplayAvailable();
  // A simulated-time run is the automatic operator's, without a view, unless told otherwise (then
  // refused).
  const bool simulated_time = args.Flag("simulated-time");
  setup.operator_kind =
      args.Value("operator").value_or(op.display && !simulated_time ? "person" : "auto");
  if (setup.operator_kind != "auto" && setup.operator_kind != "person") {
    throw UsageError("option --operator: expected auto or person, got '" + setup.operator_kind +
                     "'");
  }
  op.person = setup.operator_kind == "person";
  const std::string view =
      args.Value("view").value_or(op.display && !simulated_time ? "window" : "none");
  if (view == "window") {
    if (!op.display) {
      throw UsageError(
          "option --view window: there is no display (DISPLAY is not set or its X server is not "
          "running); use --view none, "
          "and --record FILE.mp4 to record the operator's view headless");
    }
    setup.view = ViewKind::kWindow;
  } else if (view != "none") {
    throw UsageError("option --view: expected window or none, got '" + view + "'");
  }
  if (auto record = args.Value("record")) {
    // Before anything is spawned: a recording that cannot be written is an error now, not after the
    // lap.
    const std::filesystem::path file = *record;
    const std::filesystem::path folder = file.parent_path().empty() ? "." : file.parent_path();
    CheckFileOption("record", file, "a file name such as run.mp4");
    if (!std::filesystem::is_directory(folder)) {
      throw UsageError("option --record: the folder '" + folder.string() +
                       "' does not exist; expected a file in a "
                       "folder that does");
    }
    setup.record = *record;
    if (setup.view == ViewKind::kNone) setup.view = ViewKind::kOffscreen;
  }
  if (auto s = args.Number("time-limit", 1.0, 86400.0)) {
    setup.time_limit_s = *s;
  } else if (op.person) {
    setup.time_limit_s = setup.run.person_time_limit_s;
  }
  if (auto s = args.Number("lap-limit", 1.0, 86400.0)) setup.lap_limit_s = *s;
  return op;
}

/// The vehicle, and what it drives through: the link's faults, the chase
/// camera, simulated time, its track or course, its name.
void ReadVehicle(const Args& args, SessionSetup& setup) {
  if (auto device = args.Value("device")) setup.run.device = *device;
  if (auto vehicle = args.Value("vehicle")) setup.run.vehicle = *vehicle;
  setup.vehicle = LoadVehicle(setup.run.vehicle);
  // A fault nothing can be driven through is said now, not as "did not start" or "lost" once the
  // vehicle runs.
  if (const std::string problem = LinkFaultProblem(
          setup.run.link.fault, setup.vehicle.state_rate_hz, setup.run.vehicle_timeout_s);
      !problem.empty()) {
    throw UsageError("link faults " + LinkFaultText(setup.run.link.fault) + ": " + problem);
  }
  if (args.Flag("third-person")) {
    // The chase camera draws the track the operator side hands the vehicle:
    // for any other vehicle it would draw a guess.
    if (const std::string problem = ThirdPersonProblem(setup.vehicle); !problem.empty()) {
      throw UsageError("option --third-person: " + problem);
    }
    if (setup.view == ViewKind::kNone) {
      throw UsageError(
          "option --third-person: it is drawn in the operator's view, and there is none (--view "
          "none); use --view window, or --record FILE.mp4");
    }
    setup.third_person = true;
  }
  if (args.Flag("simulated-time")) {
    // Before the rest is checked: what a simulated-time run needs, named first.
    if (const std::string problem = SimulatedTimeProblem(setup); !problem.empty()) {
      throw UsageError("option --simulated-time: " + problem);
    }
    setup.simulated_time = true;
  }
  // A blimp flies a blimp course; the robot drives a track.
  if (setup.vehicle.family() == VehicleFamily::kBlimp) {
    setup.course = LoadBlimpCourse(setup.run.track);
  } else {
    setup.track = LoadTrack(setup.run.track);
    CheckGatesFit(setup.track, setup.vehicle);
  }
  if (auto name = args.Value("vehicle-name")) {
    if (const std::string problem = VehicleNameProblem(*name); !problem.empty()) {
      throw UsageError("option --vehicle-name: expected " + problem);
    }
    setup.vehicle.name = *name;
  }
}

/// The haptic device, and what its driver needs (a trace to replay) and
/// allows (the automatic operator moves simulated arms only).
void ReadDevice(const Args& args, const Operation& op, SessionSetup& setup) {
  setup.device = LoadDevice(setup.run.device);
  const haptics::DeviceDriver& driver = haptics::DriverOf(setup.device);
  if (auto trace_in = args.Value("trace-in")) {
    if (!driver.reads_trace) {
      throw UsageError("option --trace-in: the device '" + setup.run.device.string() +
                       "' is not a replay device");
    }
    CheckFileOption("trace-in", *trace_in, "a trace `haptel run --trace FILE` recorded");
    setup.device.replay.trace = *trace_in;
  }
  if (driver.reads_trace) {
    const std::filesystem::path& trace = setup.device.replay.trace;
    if (!std::filesystem::exists(trace)) {
      throw ConfigError(setup.run.device.string() + ": key 'replay.trace': no trace '" +
                        trace.string() + "'; record one with `haptel run --trace FILE`");
    }
    if (const std::string what = NotRegularFile(trace); !what.empty()) {
      throw ConfigError(setup.run.device.string() + ": key 'replay.trace': '" + trace.string() +
                        "' is " + what + "; expected a trace `haptel run --trace FILE` recorded");
    }
  }
  if (!op.person && !driver.simulated) {
    throw UsageError(
        "option --operator auto: the automatic operator moves the simulated arms, and device '" +
        setup.device.name + "' (" + setup.device.driver +
        ") is not simulated; use --operator person");
  }
}

/// The interfaces the run may use, from the catalogue, in F1–F6 order, and
/// the one it starts with: --interface, else the configuration's; a person
/// at a simulated device has no arms to move, so the vehicle's keys. A blimp
/// flies with one; the automatic operator never switches, so it needs only
/// the one it starts with.
void ReadInterfaces(const Args& args, const Operation& op, SessionSetup& setup) {
  const VehicleFamily family = setup.vehicle.family();
  const bool blimp = family == VehicleFamily::kBlimp;
  const bool simulated_device = haptics::DriverOf(setup.device).simulated;
  std::string start = setup.run.interface;
  if (!args.Value("interface") && op.person && simulated_device)
    start = interfaces::FirstInterface(family, InterfaceInput::kKeys).name;
  if (blimp) {
    // Said as the option's mistake, before any file is read.
    const InterfaceKindInfo* kind = FindInterfaceKind(start);
    if (kind == nullptr || kind->family != VehicleFamily::kBlimp) {
      throw UsageError("option --interface " + start + ": the blimp '" +
                       setup.run.vehicle.string() + "' is flown with " +
                       InterfaceKindNames(VehicleFamily::kBlimp) +
                       " (blimp-gesture: both hands on a haptic device)");
    }
  }
  std::vector<std::string> names =
      op.person && !blimp ? setup.run.interfaces : std::vector<std::string>{start};
  auto found = std::find(names.begin(), names.end(), start);
  if (found == names.end()) {
    names.insert(names.begin(), start);
    if (names.size() > 6) names.pop_back();
    found = names.begin();
  }
  setup.start_interface = static_cast<int>(found - names.begin());
  for (const std::string& name : names)
    setup.interfaces.push_back(interfaces::LoadInterfaceSpec(setup.run, name, family));
  if (!blimp) interfaces::CheckHands(setup.interfaces, setup.device);
  const interfaces::InterfaceSpec& first =
      setup.interfaces[static_cast<size_t>(setup.start_interface)];
  if (first.manual() && !op.person) {
    throw UsageError("option --interface " + first.name +
                     ": keys and controllers are a person's; use --operator person");
  }
  if (first.is_keyboard() && setup.view != ViewKind::kWindow) {
    throw UsageError("option --interface " + first.name +
                     ": the keys are read in the view's window, and there is " +
                     std::string(op.display ? "none (--view none)" : "no display") +
                     "; use --view window, or --interface " +
                     interfaces::FirstInterface(family, InterfaceInput::kGamepad).name);
  }
  if (blimp && !first.manual() && op.person && simulated_device) {
    // The blimp gesture cockpit (thesis 8.2.2) needs both arms of a haptic
    // device; a person without one flies with keys or a game controller.
    throw UsageError(
        "option --interface " + first.name +
        ": the gesture cockpit is flown with both hands on a haptic device, and the simulated "
        "device has no arms for a person; use --device with a real one, --interface blimp-keys "
        "or blimp-gamepad, or --operator auto to watch the automatic pilot");
  }
}

/// What the run builds besides: the scene and the physics world (the
/// robot's), the device's calibration and gravity grid, the vehicle's program.
void ReadWorld(const Args& args, SessionSetup& setup) {
  if (setup.vehicle.family() == VehicleFamily::kRobot) {
    if (auto scene = args.Value("scene")) setup.run.scene = *scene;
    if (!setup.run.scene.empty())
      setup.scene = PlaceScene(LoadSceneFile(setup.run.scene), setup.run.scene_placement);
    const bool any_physics =
        std::any_of(setup.interfaces.begin(), setup.interfaces.end(),
                    [](const interfaces::InterfaceSpec& s) { return s.needs_physics(); });
    if (any_physics || setup.scene) setup.physics = LoadPhysics(setup.run.physics);
  }
  setup.calibration = DeviceCalibrationFor(setup.device);
  if (!setup.device.gravity.empty()) setup.gravity = LoadGravityGrid(setup.device.gravity);
  if (!setup.attach) setup.vehicle_program = ProgramDirectory() / "haptel-vehicle";
  if (setup.simulated_time) setup.vehicle_program.clear();  // stepped in this process
}

}  // namespace

SessionSetup RunSetupFromArgs(const Args& args) {
  SessionSetup setup;
  ReadRunOptions(args, setup);
  const Operation op = ReadOperation(args, setup);
  ReadVehicle(args, setup);
  ReadDevice(args, op, setup);
  ReadInterfaces(args, op, setup);
  ReadWorld(args, setup);
  return setup;
}

RecordedRun RunAndRecord(const SessionSetup& setup, Recorder& recorder,
                         const std::atomic<bool>& interrupted, const Recorder::AlsoSave& also,
                         const std::optional<record::TrialOfRun>& trial) {
  RecordedRun run;
  run.result = RunSession(setup, interrupted);
  // Saved, or — when the database fails at the end — kept in a file beside it.
  try {
    run.run_id = recorder.Save(run.result.record, also);
    run.result.record.id = run.run_id;
  } catch (const std::exception& e) {
    run.save_error = e.what();
    try {
      run.unsaved = record::WriteUnsavedRun(run.result.record, setup.run.database, WallNs(), trial);
      std::fprintf(stderr, "haptel: run not recorded: %s; its results are in %s\n", e.what(),
                   run.unsaved.c_str());
    } catch (const std::exception& e2) {
      std::fprintf(stderr, "haptel: run not recorded: %s; and %s\n", e.what(), e2.what());
    }
  }
  if (run.run_id != 0) {
    // The run is saved; its picture is a bonus: a failure is a warning.
    try {
      const std::filesystem::path png =
          std::filesystem::absolute(record::RunPicturePath(setup.run.database, run.run_id));
      if (setup.course) {
        record::WriteRunPicture(record::RenderBlimpRunPicture(run.result.record, *setup.course),
                                png);
      } else {
        record::DrawRunPicture(run.result.record, setup.track, png);
      }
      recorder.SetPicture(run.run_id, png);
      run.result.record.picture = png.string();
      if (setup.progress) {
        std::fprintf(stderr, "[haptel] run %lld: picture %s\n", static_cast<long long>(run.run_id),
                     png.c_str());
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel: warning: run %lld is saved without its picture: %s\n",
                   static_cast<long long>(run.run_id), e.what());
    }
  }

  return run;
}

int ExitCode(const RecordedRun& run) {
  if (run.run_id == 0) return kExitNotRecorded;
  if (!run.result.view_record_error.empty() || !run.result.can_log.error.empty())
    return kExitOutputFailed;
  return ExitCode(run.result.outcome);
}

void PrintRunSummary(std::FILE* out, const SessionSetup& setup, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
  std::fprintf(out, "haptel: %s — %s\n", ToString(run.result.outcome).c_str(),
               run.result.message.c_str());
  std::fprintf(out, "  track %s, interface %s, vehicle %s (pid %d), operator %s, device %s\n",
               r.track.c_str(), r.interface.c_str(), r.vehicle.c_str(), r.vehicle_pid,
               r.operator_kind.c_str(), r.device.c_str());
  std::fprintf(out, "  distance driven %.2f m, %zu interface switches\n", r.distance_m,
               r.switches.size());
  std::fprintf(
      out,
      "  lap time %.2f s (from the start line; %.2f s before it), gates passed %d/%d, missed %d, "
      "obstacles touched %d\n",
      r.lap_time_s, r.approach_s, r.gates_passed, r.gates_total, r.gates_missed,
      r.obstacles_touched);
  for (const GateSplit& s : r.splits) {
    if (s.split_s >= 0)
      std::fprintf(out, "    gate %d  %7.2f s  %s\n", s.gate + 1, s.split_s,
                   s.passed ? "passed" : "MISSED");
  }
  constexpr const char* kShort = " CANNOT KEEP ITS RATE";
  std::fprintf(out, "  servo %.1f Hz of %.0f Hz%s (p99 period %.0f us, %llu overruns)\n",
               r.servo_rate_hz, r.servo_target_hz, r.servo_rate_short ? kShort : "",
               r.servo_period_p99_us, static_cast<unsigned long long>(run.result.servo_overruns));
  if (run.result.physics_rate_hz > 0) {
    std::fprintf(
        out,
        "  physics %.1f Hz of %.0f Hz%s (p99 period %.0f us, longest step %.0f us, %llu hand "
        "resets), controls grasped after %.2f s\n",
        run.result.physics_rate_hz, r.physics_target_hz, r.physics_rate_short ? kShort : "",
        run.result.physics_period_p99_us, run.result.physics_step_max_us,
        static_cast<unsigned long long>(run.result.physics_hand_resets), run.result.grasp_s);
  }
  const std::string counters = NonZeroCounters(r.counters);
  std::fprintf(out, "  counters: %s\n", counters.empty() ? "all zero" : counters.c_str());
  if (ReportsControllerErrors(setup)) {
    std::fprintf(out, "  %s\n", ControllerErrorsLine(run.result.controller_errors).c_str());
  }
  std::fprintf(out, "  command round trip p50 %.2f ms, p99 %.2f ms\n", r.command_rtt_ms_p50,
               r.command_rtt_ms_p99);
  if (r.speedup > 0.0) {
    std::fprintf(
        out,
        "  simulated time: %.2f s simulated in %.2f s wall-clock, %.1fx real time (%.2f s of CPU: "
        "%.1fx per CPU second)\n",
        run.result.simulated_s, run.result.wall_s, r.speedup, run.result.cpu_s,
        run.result.cpu_s > 0.0 ? run.result.simulated_s / run.result.cpu_s : 0.0);
  }
  if (r.prediction_error_m_p95 >= 0.0) {
    std::fprintf(out, "  predicted pose against each state: error p50 %.1f mm, p95 %.1f mm%s\n",
                 r.prediction_error_m_p50 * 1e3, r.prediction_error_m_p95 * 1e3,
                 r.predict ? " (shown to the operator: --predict on)" : "");
  }
  std::fprintf(out,
               "  video %lld frames, %.1f fps, %.0f kbit/s, latency p50 %.1f ms, stale %.2f s\n",
               static_cast<long long>(r.video_frames), r.video_fps, r.video_kbps,
               r.video_latency_ms_p50, r.video_stale_s);
  if (setup.view != ViewKind::kNone) {
    std::fprintf(
        out, "  view %.1f fps (frame p99 %.1f ms), video to screen p50 %.1f ms, p99 %.1f ms\n",
        r.view_fps, r.view_frame_p99_ms, r.video_to_screen_ms_p50, r.video_to_screen_ms_p99);
  }
  if (!setup.record.empty() && !run.result.view_record_error.empty()) {
    std::fprintf(out, "  operator's view NOT recorded whole: %s\n",
                 run.result.view_record_error.c_str());
  } else if (!setup.record.empty()) {
    std::fprintf(out, "  operator's view recorded to %s (%llu frames dropped)\n",
                 setup.record.c_str(),
                 static_cast<unsigned long long>(run.result.view_record_dropped));
  }
  if (const CanLogReport& log = run.result.can_log; !log.error.empty()) {
    std::fprintf(out, "  vehicle's CAN bus log NOT recorded whole: %s; %llu frames lost\n",
                 log.error.c_str(), static_cast<unsigned long long>(log.frames_lost));
  } else if (!log.path.empty()) {
    std::fprintf(out, "  vehicle's CAN bus log %s (on its host): %llu frames\n", log.path.c_str(),
                 static_cast<unsigned long long>(log.frames));
  }
  if (run.run_id != 0) {
    std::fprintf(out, "  recorded as run %lld in %s\n", static_cast<long long>(run.run_id),
                 setup.run.database.c_str());
  } else {
    std::fprintf(
        out, "  NOT recorded in %s; results in %s\n", setup.run.database.c_str(),
        run.unsaved.empty() ? "no file either (see the error above)" : run.unsaved.c_str());
  }
  if (!r.picture.empty()) std::fprintf(out, "  picture %s\n", r.picture.c_str());
}

std::string RunJson(const SessionSetup& setup, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
  std::ostringstream o;
  o << "{\"completed\":" << (r.completed ? "true" : "false")
    << ",\"outcome\":" << JsonString(r.outcome) << ",\"message\":" << JsonString(run.result.message)
    << ",\"lap_time_s\":" << JsonNumber(r.lap_time_s) << ",\"approach_s\":"
    << (std::isfinite(r.approach_s) ? JsonNumber(r.approach_s) : std::string("null"))
    << ",\"gates_passed\":" << r.gates_passed << ",\"gates_total\":" << r.gates_total
    << ",\"gates_missed\":" << r.gates_missed << ",\"obstacles_touched\":" << r.obstacles_touched
    << ",\"vehicle\":" << JsonString(r.vehicle)
    << ",\"vehicle_kind\":" << JsonString(r.vehicle_kind) << ",\"vehicle_pid\":" << r.vehicle_pid
    << ",\"servo_rate_hz\":" << JsonNumber(r.servo_rate_hz)
    << ",\"servo_period_p99_us\":" << JsonNumber(r.servo_period_p99_us)
    << ",\"servo_overruns\":" << run.result.servo_overruns
    << ",\"servo_target_hz\":" << JsonNumber(r.servo_target_hz)
    << ",\"servo_rate_short\":" << (r.servo_rate_short ? "true" : "false")
    << ",\"command_rtt_ms_p50\":" << JsonNumber(r.command_rtt_ms_p50)
    << ",\"command_rtt_ms_p99\":" << JsonNumber(r.command_rtt_ms_p99)
    << ",\"video_frames\":" << r.video_frames << ",\"video_fps\":" << JsonNumber(r.video_fps)
    << ",\"video_latency_ms_p50\":" << JsonNumber(r.video_latency_ms_p50)
    << ",\"video_kbps\":" << JsonNumber(r.video_kbps)
    << ",\"video_stale_s\":" << JsonNumber(r.video_stale_s)
    << ",\"predict\":" << (r.predict ? "true" : "false")
    << ",\"link_fault\":" << JsonString(r.link_fault) << ",\"prediction_error_m_p50\":"
    << (r.prediction_error_m_p50 >= 0.0 ? JsonNumber(r.prediction_error_m_p50)
                                        : std::string("null"))
    << ",\"prediction_error_m_p95\":"
    << (r.prediction_error_m_p95 >= 0.0 ? JsonNumber(r.prediction_error_m_p95)
                                        : std::string("null"))
    << ",\"speedup\":" << (r.speedup > 0.0 ? JsonNumber(r.speedup) : std::string("null"))
    << ",\"simulated_s\":" << JsonNumber(run.result.simulated_s)
    << ",\"cpu_s\":" << JsonNumber(run.result.cpu_s)
    << ",\"lost_detect_s\":" << JsonNumber(run.result.lost_detect_s)
    << ",\"controller_errors\":" << run.result.controller_errors << ",\"controller_error_names\":"
    << NamesJson(ControllerErrorNames(run.result.controller_errors))
    << ",\"physics_rate_hz\":" << JsonNumber(run.result.physics_rate_hz)
    << ",\"physics_period_p99_us\":" << JsonNumber(run.result.physics_period_p99_us)
    << ",\"physics_step_max_us\":" << JsonNumber(run.result.physics_step_max_us)
    << ",\"physics_hand_resets\":" << run.result.physics_hand_resets
    << ",\"physics_target_hz\":" << JsonNumber(r.physics_target_hz)
    << ",\"physics_rate_short\":" << (r.physics_rate_short ? "true" : "false")
    << ",\"grasp_s\":" << JsonNumber(run.result.grasp_s)
    << ",\"scene_bodies\":" << run.result.scene_bodies << ",\"view_fps\":" << JsonNumber(r.view_fps)
    << ",\"view_frame_p99_ms\":" << JsonNumber(r.view_frame_p99_ms)
    << ",\"video_to_screen_ms_p50\":" << JsonNumber(r.video_to_screen_ms_p50)
    << ",\"video_to_screen_ms_p99\":" << JsonNumber(r.video_to_screen_ms_p99)
    << ",\"distance_m\":" << JsonNumber(r.distance_m)
    << ",\"operator\":" << JsonString(r.operator_kind) << ",\"device\":" << JsonString(r.device)
    << ",\"interface_switches\":" << SwitchesJson(r.switches)
    << ",\"interface\":" << JsonString(r.interface) << ",\"track\":" << JsonString(r.track)
    << ",\"counters\":" << CountersJson(r.counters)
    << ",\"recorded\":" << (run.run_id != 0 ? "true" : "false") << ",\"run_id\":" << run.run_id
    << ",\"database\":" << JsonString(setup.run.database.string())
    << ",\"unsaved_file\":" << JsonString(run.unsaved.string())
    << ",\"picture\":" << JsonString(r.picture)
    << ",\"record_error\":" << JsonString(run.result.view_record_error)
    << ",\"can_log\":" << CanLogJson(run.result.can_log) << "}";
  return o.str();
}

int RunCommand(int argc, const char* const* argv) {
  // First: a signal while the files are read ends the run as soon as it starts.
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel run", kRunUsage}, argc, argv, [&] {
    // One operator, several vehicles: its own command over the same options (fleet.hpp).
    for (int i = 1; i < argc; ++i) {
      const std::string word = argv[i];
      if (word == "--fleet" || word.rfind("--fleet=", 0) == 0)
        return RunFleetCommand(argc, argv, interrupted);
    }
    bool json = false;
    bool insecure = false;
    const SessionSetup setup = cli::ReadInput([&] {
      const Args args = ParseRunArgs(argc, argv);
      if (!args.positional().empty()) {
        throw UsageError("unexpected argument '" + args.positional()[0] +
                         "' (options start with --)");
      }
      json = args.Flag("json");
      insecure = args.Flag("insecure");
      return RunSetupFromArgs(args);
    });
    if (const std::string warning = link::InsecureLinkWarning(setup.run.link, insecure);
        !warning.empty()) {
      log::Warn(warning);
    }
    // The database before anything starts: a run it cannot take is not driven.
    // Kept open for the run, and saved into at its end.
    auto recorder = cli::ReadInput([&] { return std::make_unique<Recorder>(setup.run.database); });
    if (setup.run.link.fault.enabled) {
      link::InstallLinkDownSignal();
      if (setup.progress) {
        log::Info("link faults on what both ends receive: " + LinkFaultText(setup.run.link.fault) +
                  " (SIGUSR1 cuts the link and restores it)");
      }
    }
    const RecordedRun run = RunAndRecord(setup, *recorder, interrupted);
    PrintRunSummary(stdout, setup, run);
    if (json) std::printf("%s\n", RunJson(setup, run).c_str());
    std::fflush(stdout);
    return ExitCode(run);
  });
}

}  // namespace haptel::mediator
