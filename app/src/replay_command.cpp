// `haptel replay`: each mode is its own function (here or in a file beside
// this); ReplayCommand only picks one by its options.
#include "haptel/app/replay_command.hpp"

#include <cstdio>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/mcap/info.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/replay/drive_again.hpp"
#include "haptel/replay/view_playback.hpp"

namespace haptel::app {
namespace {

constexpr const char* kReplayUsage =
    "usage: haptel replay FILE.mcap [--speed X] [--from S] [--view window|none] [--mp4 OUT.mp4]\n"
    "       haptel replay FILE.mcap --drive [--domain D] [--attach] [--json]\n"
    "       haptel replay --info FILE.mcap [--json]\n"
    "\n"
    "Draws the operator's view of a recorded session again (haptel run --session): the\n"
    "screen's video, the hands, the wheel and lever, the HUD, the ghost and the map, as\n"
    "the live view drew them, from the file's view channel and its video. A session\n"
    "recorded without a view plays its video alone.\n"
    "In the window: space pauses, . and , step a frame on and back, the left and right\n"
    "arrows seek 5 s, Home goes back to the start, Escape or q (or closing it) ends.\n"
    "--mp4 renders every frame offscreen into OUT.mp4, as fast as the machine draws, at\n"
    "the live view's recording rate: the frames the live --record MP4 had.\n"
    "--view none reads every frame and picture without drawing (a check that the file\n"
    "reads whole, a recording killed mid-lap included) and says what it read.\n"
    "\n"
    "--drive sends the robot commands the run sent to a vehicle again, at their recorded\n"
    "times from when it first answers: the run's vehicle spawned as the run spawned it\n"
    "(its vehicle file and track, from the command line the file recorded), on the run's\n"
    "domain or --domain D, or one already running there (--attach). It times the lap on\n"
    "the run's track and says the gates passed beside the record's; it exits 0 when the\n"
    "drive passed as many gates as the record, 1 when not.\n"
    "\n"
    "--info: the session file's channels (topic, schema, encodings), message counts and\n"
    "rates, duration, chunks and their compression, attachments and metadata; a file whose\n"
    "recording was killed before it was closed is read by a scan and said to be truncated,\n"
    "with what was lost (`haptel record --recover` writes a complete copy).\n"
    "options:\n"
    "  --speed X         play at X times the recorded speed (default 1)\n"
    "  --from S          start S seconds after the record's first frame (default 0)\n"
    "  --view window|none  a window (default; needs a display), or no view at all\n"
    "  --mp4 OUT.mp4     render offscreen into OUT.mp4 instead of a window\n"
    "  --drive           send the recorded commands to a vehicle again\n"
    "  --domain D        (--drive) the DDS domain (default: the run's)\n"
    "  --attach          (--drive) drive the vehicle already running there; spawn none\n"
    "  --json    (--info, --drive) one JSON object instead of the table or the line\n";

/// The session the file's run drove, set up again from the command line
/// the file recorded, without its outputs (no view, MP4, session file).
mediator::SessionSetup RecordedSetup(const mcap::Reader& reader) {
  const std::string file = reader.path().string();
  std::string line;
  for (const mcap::MetadataIndex& index : reader.summary().metadata_indexes) {
    if (index.name != record::session::kRunMetadata) continue;
    const mcap::Metadata metadata = reader.ReadMetadata(index);
    if (const auto it = metadata.metadata.find("command_line"); it != metadata.metadata.end())
      line = it->second;
  }
  if (line.empty()) {
    throw cli::InputError(file + ": no metadata \"" + std::string(record::session::kRunMetadata) +
                          "\" with the run's command_line: which vehicle and track it drove is "
                          "not known");
  }
  const std::vector<std::string> words = cli::CommandLineWords(line);
  std::vector<std::string> run;  // from "run" on, its outputs left out
  static const std::set<std::string> kOutputs = {"--session", "--record", "--view", "--output"};
  bool started = false;
  for (size_t i = 0; i < words.size(); ++i) {
    if (!started) {
      started = words[i] == "run";
      if (started) run.push_back(words[i]);
      continue;
    }
    const std::string& w = words[i];
    const std::string name = w.substr(0, w.find('='));
    if (kOutputs.count(name) != 0) {
      if (w.find('=') == std::string::npos) ++i;  // and its value
      continue;
    }
    if (w == "--json") continue;
    run.push_back(w);
  }
  if (run.empty()) {
    throw cli::InputError(file + ": the recorded command line is not a haptel run's: " + line);
  }
  run.push_back("--view");
  run.push_back("none");
  std::vector<const char*> argv;
  for (const std::string& w : run) argv.push_back(w.c_str());
  try {
    return mediator::RunSetupFromArgs(
        mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  } catch (const cli::InputError& e) {
    throw cli::InputError(file + ": the recorded run (" + line +
                          ") cannot be set up again: " + e.what());
  }
}

}  // namespace

int ReplayDriveCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel replay --drive", kReplayUsage}, argc, argv, [&] {
    std::string path;
    std::optional<int> domain;
    bool attach = false;
    bool json = false;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"domain"}, {"drive", "attach", "json"});
      if (args.positional().size() != 1) {
        throw UsageError(args.positional().empty()
                             ? "missing the session file (FILE.mcap)"
                             : "unexpected argument '" + args.positional()[1] + "'");
      }
      path = args.positional()[0];
      domain = args.Int("domain", 0, 232);
      attach = args.Flag("attach");
      json = args.Flag("json");
    });
    const mcap::Reader reader = cli::ReadInput([&] { return mcap::Reader::Open(path); });
    const replay::RecordedDrive recorded =
        cli::ReadInput([&] { return replay::ReadRecordedDrive(reader); });
    mediator::SessionSetup setup = cli::ReadInput([&] { return RecordedSetup(reader); });
    if (domain) setup.run.link.domain_id = *domain;
    if (attach) {
      setup.attach = true;
      setup.vehicle_program.clear();
    }
    const replay::DriveReport r = replay::DriveAgain(recorded, setup, InstallStopSignals());
    if (json) {
      std::printf(
          "{\"file\":%s,\"vehicle\":%s,\"domain\":%d,\"commands_sent\":%llu,"
          "\"commands_before_up\":%llu,\"commands_s\":%s,\"gates_total\":%d,"
          "\"gates_passed\":%d,\"completed\":%s,\"lap_time_s\":%s,\"recorded_gates\":%d,"
          "\"recorded_completed\":%s,\"recorded_lap_time_s\":%s,\"watchdog_stops\":%llu,"
          "\"reproduced\":%s}\n",
          JsonString(path).c_str(), JsonString(setup.vehicle.name).c_str(),
          setup.run.link.domain_id, static_cast<unsigned long long>(r.commands_sent),
          static_cast<unsigned long long>(r.commands_before_up), JsonNumber(r.commands_s).c_str(),
          r.gates_total, r.gates_passed, r.completed ? "true" : "false",
          JsonNumber(r.lap_time_s).c_str(), r.recorded_gates,
          r.recorded_completed ? "true" : "false", JsonNumber(r.recorded_lap_time_s).c_str(),
          static_cast<unsigned long long>(r.watchdog_stops), r.Reproduced() ? "true" : "false");
    } else {
      std::printf("drove '%s' again on domain %d: %llu commands over %.1f s; gates %d of %d%s",
                  setup.vehicle.name.c_str(), setup.run.link.domain_id,
                  static_cast<unsigned long long>(r.commands_sent), r.commands_s, r.gates_passed,
                  r.gates_total, r.completed ? ", lap completed" : "");
      if (r.recorded_gates >= 0) {
        std::printf(" (the record: %d%s) - %s", r.recorded_gates,
                    r.recorded_completed ? ", lap completed" : "",
                    r.Reproduced() ? "reproduced" : "NOT reproduced");
      }
      std::printf("\n");
      if (r.watchdog_stops > 0) {
        std::printf(
            "  the vehicle's watchdog stopped it in %llu states while commands were due: this "
            "host or link starved the drive, and an open-loop path differs after it\n",
            static_cast<unsigned long long>(r.watchdog_stops));
      }
    }
    std::fflush(stdout);
    return r.Reproduced() || r.recorded_gates < 0 ? cli::kExitOk : cli::kExitFailed;
  });
}

int ReplayCommand(int argc, const char* const* argv) {
  if (cli::HasOption(argc, argv, "--info")) return ReplayInfoCommand(argc, argv);
  if (cli::HasOption(argc, argv, "--drive")) return ReplayDriveCommand(argc, argv);
  return ReplayViewCommand(argc, argv);
}

int ReplayViewCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel replay", kReplayUsage}, argc, argv, [&] {
    std::string path;
    replay::ReplayOptions options;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"speed", "from", "view", "mp4"}, {});
      if (args.positional().size() != 1) {
        throw UsageError(args.positional().empty()
                             ? "missing the session file (FILE.mcap)"
                             : "unexpected argument '" + args.positional()[1] + "'");
      }
      path = args.positional()[0];
      options.speed = args.Number("speed", 0.01, 100.0).value_or(1.0);
      options.from_s = args.Number("from", 0.0, 1e9).value_or(0.0);
      const std::string view = args.Value("view").value_or("window");
      if (view == "none") {
        options.show = replay::ReplayOptions::Show::kNone;
      } else if (view != "window") {
        throw UsageError("--view: expected window or none, not '" + view + "'");
      }
      options.mp4 = args.Value("mp4").value_or("");
      if (!options.mp4.empty() && options.show == replay::ReplayOptions::Show::kNone)
        throw UsageError("--mp4 draws the view: leave out --view none");
    });
    const mcap::Reader reader = cli::ReadInput([&] { return mcap::Reader::Open(path); });
    if (reader.recovered()) {
      std::fprintf(stderr, "haptel replay: %s was not closed (%s); replaying what it holds\n",
                   path.c_str(), reader.loss().what.c_str());
    }
    replay::ViewPlayback playback(reader);
    replay::ReplayReport report;
    if (!options.mp4.empty()) {
      report = replay::RenderReplayMp4(playback, options.from_s, options.mp4);
    } else if (options.show == replay::ReplayOptions::Show::kNone) {
      report = replay::ReadReplay(playback, options.from_s);
    } else {
      report =
          replay::PlayReplayWindow(playback, options.from_s, options.speed, InstallStopSignals());
    }
    std::printf("replayed %s: %.1f s, %llu view frames%s, %llu camera pictures", path.c_str(),
                report.duration_s, static_cast<unsigned long long>(report.frames),
                report.has_view ? "" : " (no view channel: the video alone)",
                static_cast<unsigned long long>(report.pictures));
    if (report.pictures_missing > 0 || report.pictures_undecoded > 0) {
      std::printf(" (%llu frames' pictures not in the file, %llu pictures undecoded)",
                  static_cast<unsigned long long>(report.pictures_missing),
                  static_cast<unsigned long long>(report.pictures_undecoded));
    }
    if (!options.mp4.empty()) {
      std::printf("; %llu frames into %s", static_cast<unsigned long long>(report.mp4_frames),
                  options.mp4.c_str());
    }
    std::printf("\n");
    std::fflush(stdout);
    return cli::kExitOk;
  });
}

int ReplayInfoCommand(int argc, const char* const* argv) {
  return cli::Main({"haptel replay --info", kReplayUsage}, argc, argv, [&] {
    std::string path;
    bool json = false;
    cli::ReadInput([&] {
      const Args args(argc, argv, {}, {"info", "json"});
      if (args.positional().size() != 1) {
        throw UsageError(args.positional().empty()
                             ? "missing the session file (FILE.mcap)"
                             : "unexpected argument '" + args.positional()[1] + "'");
      }
      path = args.positional()[0];
      json = args.Flag("json");
    });
    const mcap::Reader reader = cli::ReadInput([&] { return mcap::Reader::Open(path); });
    const std::string text = json ? mcap::DescribeFileJson(reader) : mcap::DescribeFile(reader);
    std::fputs(text.c_str(), stdout);
    std::fflush(stdout);
    return cli::kExitOk;
  });
}

}  // namespace haptel::app
