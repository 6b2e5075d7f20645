#include "record_bench.hpp"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bare_loop.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mediator/run_setup.hpp"
#include "haptel/mediator/session.hpp"
#include "mcap_seek.hpp"
#include "smoke.hpp"

namespace haptel::bench {
namespace {

/// One lap as `haptel run` would drive it, the view offscreen; with a
/// session file when `session` is not empty.
mediator::SessionResult Lap(const std::string& track, int domain, double time_limit_s,
                            const std::filesystem::path& session) {
  const std::string domain_text = std::to_string(domain);
  const std::vector<const char*> argv = {
      "run",     "--track", track.c_str(), "--domain", domain_text.c_str(),
      "--quiet", "--view",  "none"};
  mediator::SessionSetup setup = mediator::RunSetupFromArgs(
      mediator::ParseRunArgs(static_cast<int>(argv.size()), argv.data()));
  setup.view = mediator::ViewKind::kOffscreen;  // drawn, as a person's window would be
  setup.time_limit_s = time_limit_s;
  if (!session.empty()) {
    setup.session_file.file = session;
    mediator::DescribeSessionFile(setup);
  }
  static const std::atomic<bool> never{false};
  return mediator::RunSession(setup, never);
}

}  // namespace

int BenchRecordMain(int argc, const char* const* argv) {
  bool json = false, smoke = false;
  std::string track;
  double hours = 1.0;
  int domain = 0;
  std::filesystem::path dir;
  try {
    const Args args(argc, argv, {"track", "hours", "domain"}, {"json", kSmokeFlag});
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    track = args.Value("track").value_or(
        ShippedFile(smoke ? "config/tracks/test-short.yaml" : "config/tracks/grand-prix.yaml")
            .string());
    hours = args.Number("hours", 0.001, 10.0).value_or(smoke ? 60.0 / 3600.0 : 1.0);
    domain = args.Int("domain", 0, 232).value_or(150 + static_cast<int>(getpid() % 80));
    dir = OutputDir(smoke);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench record: %s\n", e.what());
    return 2;
  }
  const double time_limit_s = smoke ? 4.0 : 0.0;  // a smoke's laps: 4 s of each
  PrintSmokeNote("record", smoke, "4 s of the short track each, a %.0f s synthetic file, 10 seeks",
                 hours * 3600.0);

  mediator::SessionResult bare, recorded;
  const std::filesystem::path session = dir / "record-lap.mcap";
  try {
    std::fprintf(stderr, "haptel bench record: a lap without a session file (%s)\n", track.c_str());
    bare = Lap(track, domain, time_limit_s, {});
    std::fprintf(stderr, "haptel bench record: the same lap recorded into %s\n", session.c_str());
    recorded = Lap(track, domain, time_limit_s, session);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench record: %s\n", e.what());
    return 1;
  }
  const BareLoop loop = MeasureBareLoop(1000.0, 0, smoke ? 0.5 : 5.0);
  const std::filesystem::path synthetic = dir / "record-synthetic.mcap";
  const SyntheticSession written = WriteSyntheticSession(synthetic, hours * 3600.0);
  const SeekFigures seek = MeasureSeek(synthetic, smoke ? 10 : 100);

  const record::SessionFileReport& file = recorded.session_file;
  const double minutes = file.duration_s / 60.0;
  const double cpu_share = file.duration_s > 0.0 ? file.thread_cpu_s / file.duration_s : 0.0;
  const double bare_p99 = bare.record.servo_period_p99_us;
  const double recorded_p99 = recorded.record.servo_period_p99_us;
  const double loop_p99 = loop.stats.period_p99_us;

  std::printf("\nhaptel bench record (%s, view offscreen)\n\n", track.c_str());
  std::printf("  lap without / with the session file: %s / %s, %.1f s / %.1f s\n",
              ToString(bare.outcome).c_str(), ToString(recorded.outcome).c_str(),
              bare.record.lap_time_s, recorded.record.lap_time_s);
  std::printf("  session file %s: %s\n", file.saved ? "saved" : "NOT saved",
              record::SessionFileLine(file).c_str());
  std::printf("  recorder thread CPU: %.2f s over %.1f s = %.2f %% of a core (target <= 3 %%)\n",
              file.thread_cpu_s, file.duration_s, 100.0 * cpu_share);
  std::printf("  messages dropped: %llu (target 0)\n",
              static_cast<unsigned long long>(file.dropped));
  std::printf("  servo period p99: %.0f us without, %.0f us with (x%.2f); bare loop %.0f us\n",
              bare_p99, recorded_p99, bare_p99 > 0.0 ? recorded_p99 / bare_p99 : 0.0, loop_p99);
  std::printf("\n  %-36s %-28s %10s %14s %8s\n", "channel", "schema", "messages", "bytes/min",
              "dropped");
  std::ofstream csv(dir / "record.csv");
  csv << "topic,schema,messages,bytes,bytes_per_minute,dropped\n";
  for (const record::SessionChannelCount& c : file.channels) {
    const double per_minute = minutes > 0.0 ? static_cast<double>(c.bytes) / minutes : 0.0;
    std::printf("  %-36s %-28s %10llu %14.0f %8llu\n", c.topic.c_str(), c.schema.c_str(),
                static_cast<unsigned long long>(c.messages), per_minute,
                static_cast<unsigned long long>(c.dropped));
    csv << c.topic << "," << c.schema << "," << c.messages << "," << c.bytes << "," << per_minute
        << "," << c.dropped << "\n";
  }
  std::printf("  %-36s %-28s %10s %14.0f\n", "the file", "", "",
              minutes > 0.0 ? static_cast<double>(file.bytes) / minutes : 0.0);
  std::printf(
      "\n  seek, a synthetic %.2f h file (%.0f MB, %zu chunks): open %.1f ms, a second read "
      "p50 %.1f ms, p95 %.1f ms, max %.1f ms (target < 100 ms)\n",
      seek.duration_s / 3600.0, static_cast<double>(seek.file_bytes) / 1e6, seek.chunks,
      seek.open_ms, seek.seek_p50_ms, seek.seek_p95_ms, seek.seek_max_ms);
  std::printf("  written to %s\n", (dir / "record.csv").c_str());
  std::filesystem::remove(synthetic);
  if (json) {
    std::string o = "{\"track\":" + JsonString(track) +
                    ",\"saved\":" + (file.saved ? "true" : "false") +
                    ",\"cpu_share\":" + JsonNumber(cpu_share) +
                    ",\"dropped\":" + std::to_string(file.dropped) + ",\"bytes_per_minute\":" +
                    JsonNumber(minutes > 0.0 ? static_cast<double>(file.bytes) / minutes : 0.0) +
                    ",\"servo_p99_us_bare_run\":" + JsonNumber(bare_p99) +
                    ",\"servo_p99_us_recorded_run\":" + JsonNumber(recorded_p99) +
                    ",\"bare_loop_p99_us\":" + JsonNumber(loop_p99) +
                    ",\"seek_open_ms\":" + JsonNumber(seek.open_ms) +
                    ",\"seek_p95_ms\":" + JsonNumber(seek.seek_p95_ms) +
                    ",\"seek_max_ms\":" + JsonNumber(seek.seek_max_ms) +
                    ",\"synthetic_messages\":" + std::to_string(written.messages) +
                    ",\"session_file\":" + record::SessionFileJson(file) + "}";
    std::printf("%s\n", JsonLine(o, smoke).c_str());
  }
  std::fflush(stdout);
  return file.saved && bare.record.servo_rate_hz > 0.0 ? 0 : 1;
}

}  // namespace haptel::bench
