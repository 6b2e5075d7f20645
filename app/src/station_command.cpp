// `haptel station`'s command line. The station itself is station/'s
// (station_run.hpp); here are its usage, its signals, its summary, its JSON
// line and its exit code.
#include "haptel/app/station_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/security.hpp"
#include "haptel/station/station_run.hpp"
#include "haptel/station/station_view.hpp"

namespace haptel::app {

namespace {

constexpr const char* kUsage =
    "usage: haptel station --vehicle NAME --camera CAMERA [options]\n"
    "  a camera station, the thesis's Surveillance Control Room: one camera of a vehicle (the\n"
    "  blimp's surveillance camera) steered from another place than the pilot's. The camera's\n"
    "  picture fills the window; drag it to pan and tilt, the wheel or Page Up/Down zoom, the\n"
    "  arrows pan and tilt, a game controller's left stick pans and tilts and its triggers\n"
    "  zoom, space points it home, Escape ends. One station holds a camera at a time: another\n"
    "  is refused (it says who holds it, since when) until the first ends. A station never\n"
    "  drives: it sends only that camera's commands.\n"
    "\n"
    "options:\n"
    "  --vehicle NAME       the vehicle, by its name on the link (default blimp1)\n"
    "  --camera NAME        the camera to steer, by its name in the vehicle file (default\n"
    "                       surveillance)\n"
    "  --aim PAN,TILT[,ZOOM]  point the camera there once it is held (degrees, positive left\n"
    "                       and up; the zoom factor, 1 the widest)\n"
    "  --view KIND          window (default with a display) or none\n"
    "  --record FILE.mp4    record the control room's view as H.264 MP4 (offscreen without a\n"
    "                       window)\n"
    "  --session FILE.mcap  record the station into an MCAP session file: its camera commands,\n"
    "                       the vehicle's cameras, the camera's video and the view; plays with\n"
    "                       `haptel replay`\n"
    "  --time-limit S       end after S seconds\n"
    "  --domain N           DDS domain id (default 0)\n"
    "  --security DIR       DDS Security with the folder `haptel security init DIR` made; this\n"
    "                       station is identity camera-CAMERA (security init --cameras)\n"
    "  --dds-interfaces LIST  network interfaces (IPv4, comma-separated) DDS may use\n"
    "  --dds-peers LIST     the vehicles' hosts, for unicast discovery\n"
    "  --discovery-server ADDR:PORT  meet the vehicle through a Fast DDS discovery server\n"
    "  --insecure           say nothing of a link beyond this host without --security\n"
    "  --json               end with one JSON line of results on stdout\n"
    "  --quiet              say only a refusal, not the camera's changes of hands\n";

constexpr double kRadPerDeg = 0.017453292519943295;
constexpr double kDegPerRad = 57.29577951308232;

/// --aim PAN,TILT[,ZOOM], degrees and a factor.
CameraAim ParseAim(const std::string& text) {
  const std::vector<std::string> parts = SplitList(text);
  const auto bad = [&text]() {
    return UsageError(
        "option --aim: expected PAN,TILT or PAN,TILT,ZOOM (degrees; zoom >= 1), got '" + text +
        "'");
  };
  if (parts.size() != 2 && parts.size() != 3) throw bad();
  double values[3] = {0.0, 0.0, 1.0};
  for (size_t i = 0; i < parts.size(); ++i) {
    if (parts[i].empty() || DecimalPrefix(parts[i]) != parts[i].size()) throw bad();
    values[i] = std::stod(parts[i]);
  }
  if (values[2] < 1.0) throw bad();
  return {values[0] * kRadPerDeg, values[1] * kRadPerDeg, values[2]};
}

station::StationSetup SetupFromArgs(int argc, const char* const* argv, bool& json, bool& insecure) {
  const Args args(argc, argv,
                  {"vehicle", "camera", "aim", "view", "record", "session", "time-limit", "domain",
                   "security", "dds-interfaces", "dds-peers", "discovery-server"},
                  {"json", "quiet", "insecure"});
  if (!args.positional().empty())
    throw UsageError("unexpected argument '" + args.positional()[0] + "' (options start with --)");
  json = args.Flag("json");
  insecure = args.Flag("insecure");
  station::StationSetup setup;
  station::StationOptions& s = setup.station;
  s.vehicle = args.Value("vehicle").value_or("blimp1");
  if (const std::string problem = VehicleNameProblem(s.vehicle); !problem.empty())
    throw UsageError("option --vehicle: expected " + problem);
  s.camera = args.Value("camera").value_or("surveillance");
  if (const std::string problem = link::CameraIdentityProblem(s.camera); !problem.empty())
    throw UsageError("option --camera: expected " + problem);
  s.session = NewSessionId();
  s.operator_name = ProcessOperatorName("haptel station");
  setup.progress = !args.Flag("quiet");
  if (auto aim = args.Value("aim")) setup.aim = ParseAim(*aim);
  if (auto t = args.Number("time-limit", 1.0, 86400.0)) setup.time_limit_s = *t;

  LinkConfig& link = s.link;
  if (auto domain = args.Int("domain", 0, 232)) link.domain_id = *domain;
  if (auto security = args.Value("security")) link.security = *security;
  if (auto list = args.Value("dds-interfaces"))
    link.interfaces = ParseAddressOption("dds-interfaces", *list);
  if (auto list = args.Value("dds-peers")) link.peers = ParseAddressOption("dds-peers", *list);
  if (auto server = args.Value("discovery-server")) link.discovery_server = ServerOption(*server);
  if (!link.security.empty()) {
    link.security_identity = link::CameraIdentity(s.camera);
    link::CheckSecurity(link.security, link.security_identity);
  }

  const bool display = view::View::DisplayAvailable();
  const std::string view = args.Value("view").value_or(display ? "window" : "none");
  if (view == "window") {
    if (!display) {
      throw UsageError(
          "option --view window: there is no display (DISPLAY is not set or its X server is not "
          "running); use --view none, and --record FILE.mp4 to record the view headless");
    }
    setup.view = station::ViewChoice::kWindow;
  } else if (view == "none") {
    setup.view = station::ViewChoice::kNone;
  } else {
    throw UsageError("option --view: expected window or none, got '" + view + "'");
  }
  if (auto record = args.Value("record")) {
    CheckOutputFileOption("record", *record, "a file name such as surveillance.mp4");
    setup.record = *record;
  }
  if (auto session = args.Value("session")) {
    CheckFileOption("session", *session, "a file name for the session, such as station.mcap");
    setup.session_file.file = *session;
    setup.session_file.run_metadata["command_line"] = cli::CommandLine(argc, argv);
    setup.session_file.run_metadata["program"] = "haptel station";
    setup.session_file.run_metadata["vehicle"] = s.vehicle;
    setup.session_file.run_metadata["camera"] = s.camera;
  }
  return setup;
}

void PrintSummary(std::FILE* out, const station::StationSetup& setup,
                  const station::StationResult& r) {
  const station::StationFigures& f = r.figures;
  std::fprintf(out, "haptel station: %s — %s\n", station::ToString(r.outcome), r.message.c_str());
  std::fprintf(out, "  %s; held %.1f s of %.1f s, %llu commands sent\n", r.holder_line.c_str(),
               std::min(f.held_s, r.duration_s), r.duration_s,
               static_cast<unsigned long long>(f.commands_sent));
  if (r.vehicle.seq != 0)
    std::fprintf(out, "  %s\n", station::VehicleText(setup.station.vehicle, r.vehicle).c_str());
  std::fprintf(out, "  as applied: pan %+.1f deg, tilt %+.1f deg, zoom %.2fx\n",
               r.camera.applied.pan * kDegPerRad, r.camera.applied.tilt * kDegPerRad,
               r.camera.applied.zoom);
  std::fprintf(out,
               "  video %llu frames, %.1f fps, %.0f kbit/s, latency p50 %.1f ms; the last picture "
               "at pan %+.1f deg, tilt %+.1f deg, zoom %.2fx (fov %.1f deg)\n",
               static_cast<unsigned long long>(r.video.frames), r.video.fps, r.video.kbps,
               r.video.latency_ms_p50, f.picture_aim.pan * kDegPerRad,
               f.picture_aim.tilt * kDegPerRad, f.picture_aim.zoom, f.picture_fov_deg);
  if (f.command_to_picture_count > 0) {
    std::fprintf(out, "  command to picture p50 %.1f ms, p95 %.1f ms (%llu moves)\n",
                 f.command_to_picture_ms_p50, f.command_to_picture_ms_p95,
                 static_cast<unsigned long long>(f.command_to_picture_count));
  }
  if (r.view_shown) {
    std::fprintf(out, "  view %.1f fps, video to screen p50 %.1f ms\n", r.view.fps,
                 r.view.video_to_screen_ms_p50);
  }
  if (!setup.record.empty()) {
    if (r.view.record_error.empty()) {
      std::fprintf(out, "  view recorded to %s (%llu frames dropped)\n", setup.record.c_str(),
                   static_cast<unsigned long long>(r.view.record_dropped));
    } else {
      std::fprintf(out, "  view NOT recorded whole: %s\n", r.view.record_error.c_str());
    }
  }
  if (!r.session_file.file.empty())
    std::fprintf(out, "  %s\n", record::SessionFileLine(r.session_file).c_str());
}

std::string StationJson(const station::StationSetup& setup, const station::StationResult& r) {
  const station::StationFigures& f = r.figures;
  std::ostringstream o;
  o << "{\"outcome\":" << JsonString(station::ToString(r.outcome))
    << ",\"message\":" << JsonString(r.message)
    << ",\"vehicle\":" << JsonString(setup.station.vehicle)
    << ",\"camera\":" << JsonString(setup.station.camera)
    << ",\"role\":" << JsonString(station::ToString(r.camera.role))
    << ",\"held\":" << (r.held ? "true" : "false") << ",\"held_s\":" << JsonNumber(f.held_s)
    << ",\"holder\":" << JsonString(r.camera.holder)
    << ",\"holder_line\":" << JsonString(r.holder_line)
    << ",\"pan_deg\":" << JsonNumber(r.camera.applied.pan * kDegPerRad)
    << ",\"tilt_deg\":" << JsonNumber(r.camera.applied.tilt * kDegPerRad)
    << ",\"zoom\":" << JsonNumber(r.camera.applied.zoom)
    << ",\"picture_pan_deg\":" << JsonNumber(f.picture_aim.pan * kDegPerRad)
    << ",\"picture_tilt_deg\":" << JsonNumber(f.picture_aim.tilt * kDegPerRad)
    << ",\"picture_zoom\":" << JsonNumber(f.picture_aim.zoom)
    << ",\"picture_fov_deg\":" << JsonNumber(f.picture_fov_deg)
    << ",\"vehicle_states\":" << (r.vehicle.seq != 0 ? "true" : "false")
    << ",\"vehicle_line\":" << JsonString(station::VehicleText(setup.station.vehicle, r.vehicle))
    << ",\"vehicle_x\":" << JsonNumber(r.vehicle.x) << ",\"vehicle_y\":" << JsonNumber(r.vehicle.y)
    << ",\"vehicle_z\":" << JsonNumber(r.vehicle.z)
    << ",\"vehicle_heading_deg\":" << JsonNumber(r.vehicle.heading * kDegPerRad)
    << ",\"vehicle_speed\":" << JsonNumber(r.vehicle.speed)
    << ",\"commands_sent\":" << f.commands_sent
    << ",\"commands_refused\":" << r.camera.commands_refused
    << ",\"video_frames\":" << r.video.frames << ",\"video_fps\":" << JsonNumber(r.video.fps)
    << ",\"video_kbps\":" << JsonNumber(r.video.kbps)
    << ",\"video_latency_ms_p50\":" << JsonNumber(r.video.latency_ms_p50)
    << ",\"command_to_picture_ms_p50\":" << JsonNumber(f.command_to_picture_ms_p50)
    << ",\"command_to_picture_ms_p95\":" << JsonNumber(f.command_to_picture_ms_p95)
    << ",\"command_to_picture_count\":" << f.command_to_picture_count
    << ",\"view_fps\":" << JsonNumber(r.view.fps)
    << ",\"record_error\":" << JsonString(r.view.record_error)
    << ",\"session_file\":" << record::SessionFileJson(r.session_file)
    << ",\"duration_s\":" << JsonNumber(r.duration_s) << "}";
  return o.str();
}

}  // namespace

int StationCommand(int argc, const char* const* argv) {
  // First: a signal while the options are read ends the station as soon as it starts.
  const std::atomic<bool>& interrupted = InstallStopSignals();
  return cli::Main({"haptel station", kUsage}, argc, argv, [&] {
    bool json = false;
    bool insecure = false;
    const station::StationSetup setup =
        cli::ReadInput([&] { return SetupFromArgs(argc, argv, json, insecure); });
    if (const std::string warning = link::InsecureLinkWarning(setup.station.link, insecure);
        !warning.empty()) {
      log::Warn(warning);
    }
    const station::StationResult result = station::RunStation(setup, interrupted);
    PrintSummary(stdout, setup, result);
    if (json) std::printf("%s\n", StationJson(setup, result).c_str());
    std::fflush(stdout);
    return station::ExitCode(result);
  });
}

}  // namespace haptel::app
