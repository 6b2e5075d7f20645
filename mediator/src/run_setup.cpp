// The session `haptel run` drives, set up from its options, and the run of
// one recorded (what a study's trial repeats too).
#include "haptel/mediator/run_setup.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/calibration/calibration_procedure.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/security.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/prediction_score.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/record/run_picture.hpp"
#include "haptel/record/truth_record.hpp"
#include "haptel/record/unsaved_run.hpp"
#include "haptel/view/view.hpp"
#include "simulated_time.hpp"

namespace haptel::mediator {

Args ParseRunArgs(int argc, const char* const* argv) {
  return Args(argc, argv,
              {"config",       "track",    "interface",       "scene",     "vehicle-name",
               "domain",       "database", "vehicle-timeout", "trace",     "operator",
               "device",       "trace-in", "time-limit",      "lap-limit", "view",
               "record",       "vehicle",  "predict",         "localise",  "link-fault",
               "link-profile", "security", "dds-interfaces",  "dds-peers", "discovery-server",
               "fleet",        "reality",  "reality-seed",    "truth",     "session",
               "head",         "ipd-mm",   "cameras"},
              {"json", "quiet", "attach", "third-person", "simulated-time", "insecure", "stereo"});
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
  if (auto localise = args.Value("localise")) {
    if (*localise != "on" && *localise != "off")
      throw UsageError("option --localise: expected on or off, got '" + *localise + "'");
    setup.localise = *localise == "on";
  }
  if (auto predict = args.Value("predict")) {
    if (*predict != "on" && *predict != "off" && *predict != "learn" && *predict != "nominal")
      throw UsageError("option --predict: expected off, on, learn or nominal, got '" + *predict +
                       "'");
    setup.predict = *predict != "off";
    setup.predict_model =
        *predict == "nominal" ? PredictionModel::kNominal : PredictionModel::kLearn;
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
  if (auto session = args.Value("session")) {
    CheckFileOption("session", *session,
                    "a file name for the session, such as runs/sessions/lap.mcap");
    setup.session_file.file = *session;
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
    CheckOutputFileOption("record", *record, "a file name such as run.mp4");
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

/// A simulated vehicle's reality and its truth record: the path goes to the
/// vehicle (--reality, else its file's `reality:`, else lab); the operator
/// side never reads the file. The truth record is written where --truth
/// says, else in a temporary file (RemoveTemporaryTruth after the run).
constexpr const char* kDefaultReality = "lab";

void ReadReality(const Args& args, SessionSetup& setup) {
  VehicleConfig& v = setup.vehicle;
  const VehicleKindInfo& kind = v.Kind();
  const bool spawned_or_stepped = !setup.attach;
  if (!kind.simulated || !spawned_or_stepped) {
    for (const char* option : {"reality", "reality-seed", "truth"}) {
      if (args.Value(option)) {
        throw UsageError(std::string("option --") + option + ": the vehicle '" + v.file.string() +
                         "' (" + v.kind + ") " +
                         (spawned_or_stepped
                              ? "is not simulated: it has no reality of ours"
                              : "runs elsewhere (--attach): its reality is its own"));
      }
    }
    return;
  }
  if (auto reality = args.Value("reality")) {
    v.reality = RealityFile(*reality);
  } else if (v.reality.empty()) {
    v.reality = RealityFile(kDefaultReality);
  }
  if (!std::filesystem::is_regular_file(v.reality)) {
    throw UsageError("option --reality: no reality file '" + v.reality.string() +
                     "'; expected a name of config/realities/ (none, lab, harsh) or a file");
  }
  if (auto seed = args.Int("reality-seed", 0, 2147483647)) v.reality_seed = *seed;
  if (auto truth = args.Value("truth")) {
    CheckFileOption("truth", *truth, "the vehicle's truth record");
    v.truth_file = *truth;
  } else {
    static std::atomic<int> runs{0};
    v.truth_file = std::filesystem::temp_directory_path() /
                   ("haptel-truth-" + std::to_string(getpid()) + "-" +
                    std::to_string(runs.fetch_add(1)) + "-" + v.name + ".csv");
    setup.truth_temporary = true;
  }
}

/// The vehicle, and what it drives through: the link's faults, the chase
/// camera, simulated time, its track or course, its name.
void ReadVehicle(const Args& args, SessionSetup& setup) {
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
  ReadReality(args, setup);
  // A camera set-up (a study condition's): which of the vehicle's cameras stream.
  if (auto list = args.Value("cameras")) {
    std::vector<std::string> names;
    std::stringstream words(*list);
    for (std::string name; std::getline(words, name, ',');) names.push_back(name);
    if (const std::string problem = KeepOnlyCameras(setup.vehicle, names); !problem.empty())
      throw UsageError("option --cameras " + *list + ": " + problem);
  }
}

/// The device a person holds a hand interface with when the run names a
/// simulated one and --device nothing: the mouse (issue 36's default for a
/// person without a haptic device).
constexpr const char* kPersonDeviceFile = "config/devices/mouse.yaml";

/// Whether a person asked for a robot's hand interface (--interface) with
/// the run file's simulated device and a window to hold the mouse in: the
/// mouse stands in for the device they do not have. Without --interface the
/// run keeps the keys it starts a person at the simulated device with; the
/// blimp's gesture cockpit still asks for a real device (its two hands'
/// fields are its meaning; not tried with the mouse).
bool PersonTakesTheMouse(const Args& args, const Operation& op, const SessionSetup& setup) {
  if (!op.person || args.Value("device") || setup.view != ViewKind::kWindow) return false;
  const std::optional<std::string> name = args.Value("interface");
  const InterfaceKindInfo* kind = name ? FindInterfaceKind(*name) : nullptr;
  return kind != nullptr && kind->input == InterfaceInput::kHands &&
         kind->family == VehicleFamily::kRobot && setup.vehicle.family() == VehicleFamily::kRobot &&
         haptics::DriverOf(setup.device).simulated;
}

/// The haptic device, and what its driver needs (a trace to replay, the
/// view's window) and allows (the automatic operator moves simulated arms
/// only); a device that is not there is said now.
void ReadDevice(const Args& args, const Operation& op, SessionSetup& setup) {
  if (auto device = args.Value("device")) setup.run.device = *device;
  setup.device = LoadDevice(setup.run.device);
  if (PersonTakesTheMouse(args, op, setup)) {
    setup.run.device = ShippedFile(kPersonDeviceFile);
    setup.device = LoadDevice(setup.run.device);
    if (setup.progress) {
      std::fprintf(stderr,
                   "[haptel] no haptic device given: the mouse moves the hands (%s; --device "
                   "another to change)\n",
                   kPersonDeviceFile);
    }
  }
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
  if (driver.reads_window && setup.view != ViewKind::kWindow) {
    throw UsageError("option --device " + setup.run.device.string() + ": device '" +
                     setup.device.name + "' (" + setup.device.driver +
                     ") is moved with the pointer and keys in the view's window, and there is " +
                     (setup.view == ViewKind::kNone ? "none (--view none)"
                                                    : "only an offscreen view (--record)") +
                     "; use --view window");
  }
  if (const std::string missing = haptics::DeviceUnavailable(setup.device); !missing.empty()) {
    throw UsageError("option --device " + setup.run.device.string() + ": " + missing);
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

/// The head that turns the pan/tilt camera (--head, else the run file's
/// `head.source`) and the view's stereo (--stereo and --ipd-mm, else its
/// `view:`). A head other than the mouse needs a person, a camera it turns
/// (the blimp's pilot camera) and a stick nothing else flies with.
void ReadHeadAndView(const Args& args, const Operation& op, SessionSetup& setup) {
  if (auto head = args.Value("head")) {
    if (*head == "mouse") {
      setup.run.head.source = HeadSourceKind::kMouse;
    } else if (*head == "gamepad") {
      setup.run.head.source = HeadSourceKind::kGamepad;
    } else if (*head == "openxr") {
      setup.run.head.source = HeadSourceKind::kOpenXr;
    } else {
      throw UsageError("option --head: expected mouse, gamepad or openxr, got '" + *head + "'");
    }
  }
  if (args.Flag("stereo")) setup.run.view.stereo = true;
  if (auto mm = args.Number("ipd-mm", 40.0, 90.0)) setup.run.view.ipd_m = *mm / 1000.0;
  if (setup.run.view.stereo && setup.view == ViewKind::kNone) {
    throw UsageError(
        "option --stereo: it is a way of drawing the operator's view, and there is none (--view "
        "none); use --view window, or --record FILE.mp4");
  }
  const HeadSourceKind head = setup.run.head.source;
  if (head == HeadSourceKind::kMouse) return;
  const std::string asked = args.Value("head")
                                ? std::string("option --head ") + ToString(head)
                                : setup.run.file.string() + ": key 'head.source' " + ToString(head);
  if (setup.vehicle.family() != VehicleFamily::kBlimp) {
    throw UsageError(asked + ": the vehicle '" + setup.run.vehicle.string() +
                     "' has no camera the head turns (the blimp's pilot camera pans and tilts "
                     "with it); expected --head mouse");
  }
  if (!op.person) {
    throw UsageError(asked + ": the automatic pilot aims the camera itself; use --operator person");
  }
  const interfaces::InterfaceSpec& first =
      setup.interfaces[static_cast<size_t>(setup.start_interface)];
  if (head == HeadSourceKind::kGamepad && first.is_gamepad()) {
    throw UsageError(asked + ": interface '" + first.name +
                     "' flies with the controller's right stick; use --head mouse or openxr, or "
                     "--interface blimp-keys");
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
  // The device first: whether a simulated-time run may be a person's
  // depends on it (at the simulated arms nobody is).
  ReadDevice(args, op, setup);
  ReadVehicle(args, setup);
  ReadInterfaces(args, op, setup);
  ReadHeadAndView(args, op, setup);
  ReadWorld(args, setup);
  if (!setup.session_file.file.empty()) DescribeSessionFile(setup);
  return setup;
}

void TakeReality(const SessionSetup& setup, SessionResult& result) {
  const std::filesystem::path& file = setup.vehicle.truth_file;
  if (file.empty()) return;
  std::error_code ignored;
  if (std::filesystem::exists(file)) {
    try {
      const record::TruthRecord truth = record::TruthRecord::Load(file);
      result.reality = truth.reality();
      result.reality_seed = truth.seed();
      // The lap judged again from where the vehicle truly went.
      if (setup.course) {
        ScorePrediction(truth, nullptr, result);
        JudgeLapOnTruth(truth, *setup.course, result);
      } else {
        const Track track(setup.track);
        ScorePrediction(truth, &track, result);
        JudgeLapOnTruth(truth, track, result);
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "haptel: warning: the vehicle's truth record: %s\n", e.what());
    }
  }
  if (setup.truth_temporary) std::filesystem::remove(file, ignored);
}

void DescribeSessionFile(SessionSetup& setup) {
  std::map<std::string, std::string>& m = setup.session_file.run_metadata;
  m["configuration"] = setup.run.name;
  m["vehicle"] = setup.vehicle.name;
  m["vehicle_kind"] = setup.vehicle.kind;
  m["device"] = setup.device.name;
  m["operator"] = setup.operator_kind;
  std::string interfaces;
  for (const interfaces::InterfaceSpec& spec : setup.interfaces)
    interfaces += (interfaces.empty() ? "" : ",") + spec.name;
  m["interfaces"] = interfaces;
  std::vector<std::filesystem::path>& files = setup.session_file.attachments;
  files.clear();
  for (const std::filesystem::path& file :
       {setup.run.file, setup.vehicle.file, setup.device.file, setup.track.file}) {
    std::error_code ec;
    if (!file.empty() && std::filesystem::is_regular_file(file, ec) &&
        std::find(files.begin(), files.end(), file) == files.end())
      files.push_back(file);
  }
}

RecordedRun RunAndRecord(const SessionSetup& setup, Recorder& recorder,
                         const std::atomic<bool>& interrupted, const Recorder::AlsoSave& also,
                         const std::optional<record::TrialOfRun>& trial) {
  RecordedRun run;
  run.result = RunSession(setup, interrupted);
  TakeReality(setup, run.result);
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

}  // namespace haptel::mediator
