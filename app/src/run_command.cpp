// `haptel run`'s command line. The session is set up from its options, run
// and recorded by the mediator (mediator/run_setup.hpp); here are its usage,
// its signals, its summary, its JSON line and its exit code.
#include "haptel/app/run_command.hpp"

#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/security.hpp"
#include "haptel/mediator/controller_errors.hpp"
#include "haptel/mediator/prediction_score.hpp"
#include "haptel/mediator/run_counters.hpp"

namespace haptel::app {

using mediator::CanLogReport;
using mediator::GateSplit;
using mediator::RecordedRun;
using mediator::Recorder;
using mediator::RunRecord;
using mediator::SessionSetup;
using mediator::ViewKind;

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
    "  --predict off|on|learn|nominal\n"
    "                       the predictive display (default off): the operator sees the vehicle\n"
    "                       where its model says it is now, from the delayed states and the\n"
    "                       commands sent since; on = learn: the vehicle file's model with what\n"
    "                       is estimated of the vehicle while it drives (the robot's tread gains\n"
    "                       and track width, the blimp's wind); nominal: the file's alone. The\n"
    "                       model's error and estimates are reported either way\n"
    "  --localise on|off    a robot whose states carry range scans is localised on the track\n"
    "                       (default on): its odometry corrected against the walls and posts,\n"
    "                       for the prediction, the gates and the view; off: its odometry alone\n"
    "  --view KIND          window (default with a display) or none\n"
    "  --third-person       beside the camera's picture, a chase camera's view of the robot on\n"
    "                       its track (a simulated robot only: its track is known here)\n"
    "  --record FILE.mp4    record the operator's view as H.264 MP4 (offscreen without a window)\n"
    "  --head mouse|gamepad|openxr\n"
    "                       what turns the blimp pilot's camera (overrides the run file's\n"
    "                       head.source): mouse (the default: drag with the right button, Home\n"
    "                       looks ahead), gamepad (the right stick turns it at a rate, clicking\n"
    "                       the stick looks ahead) or openxr (a head-mounted display's pose; with\n"
    "                       no OpenXR runtime the run says so and the mouse turns it)\n"
    "  --stereo             side by side for a head-mounted display: the world from each eye\n"
    "                       in its half of the view (the run file's view.stereo)\n"
    "  --ipd-mm MM          the eyes' distance apart for --stereo (default 64; view.ipd_m)\n"
    "  --cameras LIST       which of the vehicle's cameras stream (a camera set-up), e.g. pilot\n"
    "                       or pilot,surveillance; the driven camera always (default: all)\n"
    "  --scene FILE         haptic scene for the hands (YAML, or the thesis's MHaptic .xml),\n"
    "                       moved by the configuration's scene_placement\n"
    "  --vehicle FILE       vehicle configuration the spawned vehicle runs (overrides 'vehicle'),\n"
    "                       e.g. config/vehicles/can-robot-sim.yaml (the CAN code path)\n"
    "  --vehicle-name NAME  vehicle name in DDS topic names\n"
    "  --reality NAME|FILE  the simulated vehicle's hidden truth: config/realities/NAME.yaml\n"
    "                       (none: the twin the operator predicts with; lab, the default: a\n"
    "                       Lego tank on a lab floor, the blimp in a breeze; harsh) or a file;\n"
    "                       passed to the vehicle, never read here (overrides its 'reality')\n"
    "  --reality-seed N     the reality's draws (default: the reality file's seed)\n"
    "  --truth FILE         keep the vehicle's truth record here (its drawn reality, then its\n"
    "                       true pose at the control rate; default: a temporary file, removed)\n"
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
    "  --session FILE       record the whole run into an MCAP session file (the folder is\n"
    "                       created): every DDS sample sent and received, the video, the\n"
    "                       servo ticks, the events, the metadata and configuration files;\n"
    "                       opens in Foxglove or Lichtblick, plays with `haptel replay`\n"
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
std::string CanLogJson(const CanLogReport& log) {
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

/// A figure in metres or seconds, null when unknown (negative or NaN).
std::string NumberOrNull(double value) {
  return std::isfinite(value) && value >= 0.0 ? haptel::JsonNumber(value) : std::string("null");
}

/// {"left_gain":{"estimate":…,"truth":…,"known_s":…},…}: truth null without
/// a truth record, known_s null when never known.
std::string EstimatedJson(const std::vector<haptel::record::EstimatedParameter>& estimated) {
  std::string out = "{";
  for (const auto& p : estimated) {
    if (out.size() > 1) out += ",";
    out += haptel::JsonString(p.name) + ":{\"estimate\":" + haptel::JsonNumber(p.estimate) +
           ",\"truth\":" +
           (std::isfinite(p.truth) ? haptel::JsonNumber(p.truth) : std::string("null")) +
           ",\"known_s\":" + NumberOrNull(p.known_s) + "}";
  }
  return out + "}";
}

/// A localised robot's map against the truth (RunRecord::map_estimated):
/// {"features":N,"learnt_m_rms":…,"file_m_rms":…}, null when not scored.
std::string MapJson(const haptel::record::RunRecord& r) {
  const haptel::record::RunRecord::MapEstimate& m = r.map_estimated;
  if (m.features == 0) return "null";
  return "{\"features\":" + std::to_string(m.features) +
         ",\"learnt_m_rms\":" + NumberOrNull(m.learnt_m_rms) +
         ",\"file_m_rms\":" + NumberOrNull(m.file_m_rms) + "}";
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

/// The frame the truth is scored in (prediction_score.hpp): {"frame":"map",
/// "rotation_deg":…,"offset_m":[x,y],"features":N,"residual_m_rms":…}, the
/// rigid fit of the as-built track onto its file; "frame":"world" (the fit the
/// identity) when the reality displaced nothing or there is no truth.
std::string TruthFrameJson(const haptel::record::RunRecord& r) {
  const haptel::record::RunRecord::MapFrameFit& f = r.map_fit;
  if (f.features == 0) return "{\"frame\":\"world\"}";
  return "{\"frame\":\"map\",\"rotation_deg\":" + haptel::JsonNumber(f.rotation_deg) +
         ",\"offset_m\":[" + haptel::JsonNumber(f.offset_x_m) + "," +
         haptel::JsonNumber(f.offset_y_m) + "],\"features\":" + std::to_string(f.features) +
         ",\"residual_m_rms\":" + haptel::JsonNumber(f.residual_m_rms) + "}";
}

/// The lap judged from the truth record: ,"lap_time_truth_s":…,
/// "lap_time_truth_projected":… (true: its finish projected, not crossed),
/// "completed_truth":…,"gates_truth_passed":…,"gates_truth_missed":…,
/// "gates_disagree":["gate 3: …"] (all null when there is no truth to judge from).
std::string TruthLapJson(const haptel::record::RunRecord& r) {
  const haptel::record::TruthLap& t = r.truth_lap;
  if (!t.judged) {
    return ",\"lap_time_truth_s\":null,\"lap_time_truth_projected\":null,"
           "\"completed_truth\":null,\"gates_truth_passed\":null,"
           "\"gates_truth_missed\":null,\"gates_disagree\":null";
  }
  return ",\"lap_time_truth_s\":" + NumberOrNull(t.lap_time_s) +
         ",\"lap_time_truth_projected\":" + (t.projected ? "true" : "false") +
         ",\"completed_truth\":" + (t.completed ? "true" : "false") +
         ",\"gates_truth_passed\":" + std::to_string(t.gates_passed) +
         ",\"gates_truth_missed\":" + std::to_string(t.gates_missed) +
         ",\"gates_disagree\":" + NamesJson(haptel::mediator::TruthLapDisagreements(r));
}

/// Whether the run's vehicle has a servo controller that reports errors (a Maestro).
bool ReportsControllerErrors(const SessionSetup& setup) {
  const haptel::VehicleKindInfo* kind = haptel::FindVehicleKind(setup.vehicle.kind);
  return kind != nullptr && kind->Uses(haptel::kServoSection) &&
         setup.vehicle.servo.protocol == haptel::ServoProtocol::kMaestro;
}

}  // namespace

int ExitCode(const RecordedRun& run) {
  if (run.run_id == 0) return cli::kExitNotRecorded;
  if (!run.result.view_record_error.empty() || !run.result.can_log.error.empty())
    return cli::kExitOutputFailed;
  if (const auto& file = run.result.session_file; !file.file.empty() && !file.saved)
    return cli::kExitOutputFailed;
  return mediator::ExitCode(run.result.outcome);
}

namespace {

/// The lap: its time, gates and splits, and the lap judged from the truth.
void PrintLap(std::FILE* out, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
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
  if (const haptel::record::TruthLap& t = r.truth_lap; t.judged) {
    // The live lap is the vehicle's odometry's; where the truth is known,
    // the lap it truly drove.
    if (t.completed) {
      std::fprintf(out,
                   "  judged from the truth: lap time %.2f s%s, gates passed %d/%d, missed %d\n",
                   t.lap_time_s, t.projected ? " (finish projected)" : "", t.gates_passed,
                   r.gates_total, t.gates_missed);
    } else {
      std::fprintf(out,
                   "  judged from the truth: lap NOT completed, gates passed %d/%d, missed %d\n",
                   t.gates_passed, r.gates_total, t.gates_missed);
    }
    for (const std::string& line : mediator::TruthLapDisagreements(r))
      std::fprintf(out, "    %s\n", line.c_str());
  }
}

/// The loops' rates, the counters and the link's round trip.
void PrintLoops(std::FILE* out, const SessionSetup& setup, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
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
  const std::string counters = mediator::NonZeroCounters(r.counters);
  std::fprintf(out, "  counters: %s\n", counters.empty() ? "all zero" : counters.c_str());
  if (ReportsControllerErrors(setup)) {
    std::fprintf(out, "  %s\n",
                 mediator::ControllerErrorsLine(run.result.controller_errors).c_str());
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
}

/// The hidden reality, the prediction and the pose scored against it, the estimates.
void PrintPrediction(std::FILE* out, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
  if (!run.result.reality.empty()) {
    std::fprintf(out, "  the vehicle's reality: %s, seed %llu (hidden from the operator side)\n",
                 run.result.reality.c_str(),
                 static_cast<unsigned long long>(run.result.reality_seed));
  }
  if (r.prediction_error_odometry_m_p95 >= 0.0 || r.prediction_error_m_p95 >= 0.0) {
    std::fprintf(out, "  prediction (%s model%s):", r.predict_model.c_str(),
                 r.predict ? ", shown to the operator" : ", not shown");
    if (r.prediction_error_m_p95 >= 0.0 && r.map_fit.features > 0) {
      std::fprintf(out,
                   " error against the truth in the map's frame p50 %.1f mm, p95 %.1f mm (in the "
                   "world's p50 %.1f mm, p95 %.1f mm);",
                   r.prediction_error_m_p50 * 1e3, r.prediction_error_m_p95 * 1e3,
                   r.prediction_error_world_m_p50 * 1e3, r.prediction_error_world_m_p95 * 1e3);
    } else if (r.prediction_error_m_p95 >= 0.0) {
      std::fprintf(out, " error against the truth p50 %.1f mm, p95 %.1f mm;",
                   r.prediction_error_m_p50 * 1e3, r.prediction_error_m_p95 * 1e3);
    } else {
      std::fprintf(out, " no truth to score against (not a simulated vehicle);");
    }
    if (r.prediction_error_odometry_m_p95 >= 0.0) {
      std::fprintf(out, " against each state (odometry) p50 %.1f mm, p95 %.1f mm",
                   r.prediction_error_odometry_m_p50 * 1e3,
                   r.prediction_error_odometry_m_p95 * 1e3);
    }
    std::fprintf(out, "\n");
  }
  if (r.odometry_error_m_p95 >= 0.0) {
    std::fprintf(out,
                 "  the robot's pose against the truth: %s p50 %.1f mm, p95 %.1f mm; its odometry "
                 "p50 %.1f mm, p95 %.1f mm\n",
                 r.localised ? "localised on the track" : "odometry (not localised)",
                 r.localisation_error_m_p50 * 1e3, r.localisation_error_m_p95 * 1e3,
                 r.odometry_error_m_p50 * 1e3, r.odometry_error_m_p95 * 1e3);
    if (r.map_fit.features > 0) {
      std::fprintf(out,
                   "  the track as built against its file: turned %.3f deg, offset %.1f, %.1f mm "
                   "(the map's frame: the best rigid fit of %d features), each feature %.1f mm rms "
                   "from the map beyond it; the localised pose in the world's frame p50 %.1f mm, "
                   "p95 %.1f mm\n",
                   r.map_fit.rotation_deg, r.map_fit.offset_x_m * 1e3, r.map_fit.offset_y_m * 1e3,
                   r.map_fit.features, r.map_fit.residual_m_rms * 1e3,
                   r.localisation_error_world_m_p50 * 1e3, r.localisation_error_world_m_p95 * 1e3);
    }
    const haptel::record::RunRecord::MapEstimate& m = r.map_estimated;
    if (m.features > 0 && m.learnt_m_rms != m.file_m_rms) {
      std::fprintf(out,
                   "  the map learnt: its %d wall corners and posts %.1f mm rms from where they "
                   "truly stand (the file's %.1f mm)\n",
                   m.features, m.learnt_m_rms * 1e3, m.file_m_rms * 1e3);
    }
    if (r.localiser_scans_refused > 0) {
      std::fprintf(out, "  the localiser refused %lld scans that disagreed with the map\n",
                   static_cast<long long>(r.localiser_scans_refused));
    }
  }
  for (const haptel::record::EstimatedParameter& p : r.estimated) {
    std::fprintf(out, "  estimated %s %.4g", p.name.c_str(), p.estimate);
    if (std::isfinite(p.truth)) std::fprintf(out, " (truth %.4g)", p.truth);
    if (std::isfinite(p.known_s)) {
      std::fprintf(out, ", known after %.1f s\n", p.known_s);
    } else {
      std::fprintf(out, ", never known: the vehicle file's value\n");
    }
  }
}

/// The video and the view, and where the run's files and record went.
void PrintOutputs(std::FILE* out, const SessionSetup& setup, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
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
  if (!run.result.session_file.file.empty())
    std::fprintf(out, "  %s\n", record::SessionFileLine(run.result.session_file).c_str());
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

}  // namespace

void PrintRunSummary(std::FILE* out, const SessionSetup& setup, const RecordedRun& run) {
  const RunRecord& r = run.result.record;
  std::fprintf(out, "haptel: %s — %s\n", ToString(run.result.outcome).c_str(),
               run.result.message.c_str());
  std::fprintf(out, "  track %s, interface %s, vehicle %s (pid %d), operator %s, device %s\n",
               r.track.c_str(), r.interface.c_str(), r.vehicle.c_str(), r.vehicle_pid,
               r.operator_kind.c_str(), r.device.c_str());
  std::fprintf(out, "  distance driven %.2f m, %zu interface switches, not engaged %.1f s\n",
               r.distance_m, r.switches.size(), r.disengaged_s);
  if (std::isfinite(r.pseudo_haptic_gain_mean) || r.ff_effects_played > 0) {
    std::fprintf(out,
                 "  device: pseudo-haptic gain mean %.2f, force-feedback effects played %lld\n",
                 r.pseudo_haptic_gain_mean, static_cast<long long>(r.ff_effects_played));
  }
  PrintLap(out, run);
  PrintLoops(out, setup, run);
  PrintPrediction(out, run);
  PrintOutputs(out, setup, run);
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
    << ",\"prediction_error_world_m_p50\":" << NumberOrNull(r.prediction_error_world_m_p50)
    << ",\"prediction_error_world_m_p95\":" << NumberOrNull(r.prediction_error_world_m_p95)
    << ",\"truth_frame\":" << TruthFrameJson(r)
    << ",\"predict_model\":" << JsonString(r.predict_model)
    << ",\"prediction_error_odometry_m_p50\":" << NumberOrNull(r.prediction_error_odometry_m_p50)
    << ",\"prediction_error_odometry_m_p95\":" << NumberOrNull(r.prediction_error_odometry_m_p95)
    << ",\"localised\":" << (r.localised ? "true" : "false") << ",\"localiser_scans_refused\":"
    << (r.localiser_scans_refused >= 0 ? std::to_string(r.localiser_scans_refused) : "null")
    << ",\"localisation_error_m_p50\":" << NumberOrNull(r.localisation_error_m_p50)
    << ",\"localisation_error_m_p95\":" << NumberOrNull(r.localisation_error_m_p95)
    << ",\"localisation_error_world_m_p50\":" << NumberOrNull(r.localisation_error_world_m_p50)
    << ",\"localisation_error_world_m_p95\":" << NumberOrNull(r.localisation_error_world_m_p95)
    << ",\"odometry_error_m_p50\":" << NumberOrNull(r.odometry_error_m_p50)
    << ",\"odometry_error_m_p95\":" << NumberOrNull(r.odometry_error_m_p95)
    << ",\"estimated\":" << EstimatedJson(r.estimated) << ",\"estimated_map\":" << MapJson(r)
    << TruthLapJson(r)
    << ",\"speedup\":" << (r.speedup > 0.0 ? JsonNumber(r.speedup) : std::string("null"))
    << ",\"simulated_s\":" << JsonNumber(run.result.simulated_s)
    << ",\"cpu_s\":" << JsonNumber(run.result.cpu_s)
    << ",\"lost_detect_s\":" << JsonNumber(run.result.lost_detect_s)
    << ",\"controller_errors\":" << run.result.controller_errors << ",\"controller_error_names\":"
    << NamesJson(mediator::ControllerErrorNames(run.result.controller_errors))
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
    << ",\"head_source\":" << JsonString(run.result.head_source)
    << ",\"head_fallback\":" << JsonString(run.result.head_fallback)
    << ",\"cameras\":" << JsonString(CameraNames(setup.vehicle))
    << ",\"disengaged_s\":" << JsonNumber(r.disengaged_s)
    << ",\"pseudo_haptic_gain_mean\":" << JsonNumber(r.pseudo_haptic_gain_mean)
    << ",\"ff_effects_played\":" << r.ff_effects_played
    << ",\"interface_switches\":" << SwitchesJson(r.switches)
    << ",\"interface\":" << JsonString(r.interface) << ",\"track\":" << JsonString(r.track)
    << ",\"counters\":" << CountersJson(r.counters)
    << ",\"recorded\":" << (run.run_id != 0 ? "true" : "false") << ",\"run_id\":" << run.run_id
    << ",\"database\":" << JsonString(setup.run.database.string())
    << ",\"unsaved_file\":" << JsonString(run.unsaved.string())
    << ",\"picture\":" << JsonString(r.picture)
    << ",\"record_error\":" << JsonString(run.result.view_record_error)
    << ",\"can_log\":" << CanLogJson(run.result.can_log)
    << ",\"commands_sent\":" << run.result.commands_sent
    << ",\"states_received\":" << run.result.states_received
    << ",\"servo_ticks\":" << run.result.servo_arm_ticks
    << ",\"session_file\":" << record::SessionFileJson(run.result.session_file) << ",\"reality\":"
    << (run.result.reality.empty() ? std::string("null")
                                   : "{\"name\":" + JsonString(run.result.reality) + ",\"seed\":" +
                                         std::to_string(run.result.reality_seed) + "}")
    << "}";
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
      const Args args = mediator::ParseRunArgs(argc, argv);
      if (!args.positional().empty()) {
        throw UsageError("unexpected argument '" + args.positional()[0] +
                         "' (options start with --)");
      }
      json = args.Flag("json");
      insecure = args.Flag("insecure");
      SessionSetup s = mediator::RunSetupFromArgs(args);
      s.session_file.run_metadata["command_line"] = cli::CommandLine(argc, argv);
      return s;
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
    const RecordedRun run = mediator::RunAndRecord(setup, *recorder, interrupted);
    PrintRunSummary(stdout, setup, run);
    if (json) std::printf("%s\n", RunJson(setup, run).c_str());
    std::fflush(stdout);
    return ExitCode(run);
  });
}

}  // namespace haptel::app
