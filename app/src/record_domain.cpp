// `haptel record --domain D [--vehicle NAME] FILE.mcap`: a separate process
// that records what it can see on a DDS domain into a session file, as
// `ros2 bag record` does: every Haptel topic (haptel/<vehicle>/...) whose
// writer it discovers, each read with its writer's type as soon as it is
// seen, the video as Foxglove's video. What DDS Security does not grant
// this participant (another operator's commands) is skipped and said.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "haptel/app/record_command.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/command_line.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/discovered_writers.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/security.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/record/session_recorder.hpp"

namespace haptel::app {
namespace {

constexpr const char* kUsage =
    "usage: haptel record --domain D [--vehicle NAME] [options] FILE.mcap\n"
    "       haptel record --recover IN.mcap OUT.mcap\n"
    "\n"
    "Records what this host can see on DDS domain D into FILE.mcap (the folder is created),\n"
    "like `ros2 bag record`: every Haptel topic (haptel/<vehicle>/...) whose writer it\n"
    "discovers (or only NAME's), each sample as the CDR bytes that crossed the link, the\n"
    "video as foxglove.CompressedVideo or CompressedImage. Commands only where DDS Security\n"
    "grants this host's identity their topic. SIGINT or SIGTERM ends it with a complete file.\n"
    "\n"
    "  --domain D           the DDS domain (0..232)\n"
    "  --vehicle NAME       only this vehicle's topics\n"
    "  --config FILE        the link's settings (interfaces, peers, security) from this run\n"
    "                       file (default config/haptel.yaml)\n"
    "  --security DIR       DDS Security (haptel security), as haptel run\n"
    "  --duration S         stop after S seconds (default: until a signal)\n"
    "  --json               end with one JSON line: the file, its channels and counts\n";

/// A reader made for a discovered topic: taps its samples, keeps nothing.
using ReaderMaker =
    std::function<std::shared_ptr<void>(link::Participant&, const std::string& topic)>;

template <typename Msg, typename PubSub>
ReaderMaker MakerOf() {
  return [](link::Participant& p, const std::string& topic) -> std::shared_ptr<void> {
    // Best effort, keep last, volatile: matches every writer's QoS (a
    // reliable or transient-local writer serves a best-effort reader too).
    return std::make_shared<link::Reader<Msg, PubSub>>(p, topic, link::Profile::kVideo,
                                                       [](const Msg&) {});
  };
}

/// The DDS types Haptel writes, by their names on the wire.
const std::map<std::string, ReaderMaker>& Makers() {
  static const std::map<std::string, ReaderMaker> makers = {
      {"haptel::msg::TreadCommand", MakerOf<msg::TreadCommand, msg::TreadCommandPubSubType>()},
      {"haptel::msg::VehicleState", MakerOf<msg::VehicleState, msg::VehicleStatePubSubType>()},
      {"haptel::msg::VideoFrame", MakerOf<msg::VideoFrame, msg::VideoFramePubSubType>()},
      {"haptel::msg::VideoFeedback", MakerOf<msg::VideoFeedback, msg::VideoFeedbackPubSubType>()},
      {"haptel::msg::CanLogStatus", MakerOf<msg::CanLogStatus, msg::CanLogStatusPubSubType>()},
      {"haptel::msg::SelectedSource",
       MakerOf<msg::SelectedSource, msg::SelectedSourcePubSubType>()},
      {"haptel::msg::BlimpCommand", MakerOf<msg::BlimpCommand, msg::BlimpCommandPubSubType>()},
      {"haptel::msg::BlimpState", MakerOf<msg::BlimpState, msg::BlimpStatePubSubType>()},
      // The cameras (issue 38): a station's commands, the vehicle's status
      // of its cameras; each camera's video is a VideoFrame on its own topic.
      {"haptel::msg::CameraCommand", MakerOf<msg::CameraCommand, msg::CameraCommandPubSubType>()},
      {"haptel::msg::CameraStatus", MakerOf<msg::CameraStatus, msg::CameraStatusPubSubType>()},
  };
  return makers;
}

/// Whether `topic` is one of Haptel's, of `vehicle` when one is named.
bool Wanted(const std::string& topic, const std::string& vehicle) {
  if (topic.rfind("haptel/", 0) != 0) return false;
  return vehicle.empty() || topic.rfind("haptel/" + vehicle + "/", 0) == 0;
}

}  // namespace

int RecordDomainCommand(int argc, const char* const* argv) {
  const std::atomic<bool>& stop = InstallStopSignals();
  return cli::Main({"haptel record", kUsage}, argc, argv, [&] {
    std::filesystem::path file;
    std::string vehicle;
    double duration_s = 0.0;
    bool json = false;
    RunConfig run;
    cli::ReadInput([&] {
      const Args args(argc, argv, {"domain", "vehicle", "config", "security", "duration"},
                      {"json"});
      if (args.positional().size() != 1) {
        throw UsageError(args.positional().empty()
                             ? "expected the session file to write, e.g. lap.mcap"
                             : "unexpected argument '" + args.positional()[1] + "'");
      }
      file = args.positional()[0];
      if (const std::string what = NotRegularFile(file); !what.empty()) {
        throw UsageError("the session file '" + file.string() + "' is " + what +
                         "; expected a file name such as lap.mcap");
      }
      run = LoadRun(args.Value("config").value_or(ShippedFile("config/haptel.yaml").string()));
      const auto domain = args.Int("domain", 0, 232);
      if (!domain) throw UsageError("expected --domain D (the DDS domain to record)");
      run.link.domain_id = *domain;
      if (auto security = args.Value("security")) run.link.security = *security;
      if (!run.link.security.empty())
        link::CheckSecurity(run.link.security, link::OperatorIdentity());
      vehicle = args.Value("vehicle").value_or("");
      duration_s = args.Number("duration", 0.1, 1e7).value_or(0.0);
      json = args.Flag("json");
    });

    record::SessionFileOptions options;
    options.file = file;
    options.run_metadata = {{"command_line", cli::CommandLine(argc, argv)},
                            {"recorder", "haptel record"},
                            {"domain", std::to_string(run.link.domain_id)},
                            {"vehicle", vehicle}};
    record::SessionRecorder recorder(options);
    LinkConfig link = run.link;
    link.security_identity = link::OperatorIdentity();
    link::DiscoveredWriters discovery;
    link::Participant participant(link, "haptel-record", &discovery);
    participant.SetTap(&recorder);

    std::vector<std::shared_ptr<void>> readers;
    std::set<std::string> seen;
    const int64_t start_ns = MonotonicNs();
    log::Info("recording domain " + std::to_string(run.link.domain_id) +
              (vehicle.empty() ? "" : ", vehicle '" + vehicle + "'") + " into " + file.string() +
              " (Ctrl-C ends it)");
    while (!stop.load()) {
      for (const auto& [topic, type] : discovery.Take()) {
        if (!Wanted(topic, vehicle) || !seen.insert(topic).second) continue;
        const auto maker = Makers().find(type);
        if (maker == Makers().end()) {
          log::Warn("topic " + topic + ": type " + type + " is not Haptel's; not recorded");
          continue;
        }
        try {
          readers.push_back(maker->second(participant, topic));
          log::Info("recording " + topic + " (" + type + ")");
        } catch (const std::exception& e) {
          // DDS Security grants this identity no reader there (another's commands).
          log::Warn("topic " + topic + " not recorded: " + e.what());
        }
      }
      if (duration_s > 0.0 && NsToS(MonotonicNs() - start_ns) >= duration_s) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    participant.get()->set_listener(nullptr);  // before `discovery` goes
    readers.clear();                           // no callback runs past here
    const record::SessionFileReport report = recorder.Close();
    std::printf("%s\n", record::SessionFileLine(report).c_str());
    if (json) std::printf("%s\n", record::SessionFileJson(report).c_str());
    std::fflush(stdout);
    return report.saved ? cli::kExitOk : cli::kExitFailed;
  });
}

}  // namespace haptel::app
