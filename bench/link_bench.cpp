#include "link_bench.hpp"

#include <signal.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "haptel/config/link.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/histogram.hpp"
#include "haptel/core/json.hpp"
#include "haptel/core/stop_signals.hpp"
#include "haptel/link/security.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "plot.hpp"
#include "smoke.hpp"

namespace haptel::bench {

namespace {

constexpr double kRateHz = 100.0;

double Number(const std::string& json, const std::string& key) {
  const std::string v = JsonFieldOf(json, key);
  return v.empty() || v == "null" ? std::nan("") : std::stod(v);
}

std::vector<double> ParseList(const std::string& option, const std::string& text) {
  std::vector<double> out;
  for (const std::string& item : SplitList(text)) {
    try {
      out.push_back(std::stod(item));
    } catch (const std::exception&) {
      throw UsageError("option --" + option + ": expected comma-separated numbers, got '" + text +
                       "'");
    }
    if (!(out.back() >= 0.0)) throw UsageError("option --" + option + ": expected numbers >= 0");
  }
  if (out.empty()) throw UsageError("option --" + option + ": expected at least one number");
  return out;
}

/// `haptel-bench link --echo --domain D`: echoes every ping as a pong until stopped.
int Echo(int domain) {
  const std::atomic<bool>& stop = InstallStopSignals();
  LinkConfig config;
  config.domain_id = domain;
  link::Participant participant(config, "haptel-bench-echo");
  link::TreadCommandWriter pong(participant, "bench/pong", link::Profile::kCommand);
  msg::TreadCommand copy;
  link::TreadCommandReader ping(participant, "bench/ping", link::Profile::kCommand,
                                [&](const msg::TreadCommand& c) {
                                  copy = c;
                                  pong.Write(copy);
                                });
  std::printf("echo up\n");
  std::fflush(stdout);
  while (!stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return 0;
}

struct RttFigures {
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  uint64_t samples = 0;
  double video_p50_ms = std::nan("");  ///< capture -> decoded (Haptel's link only)
  double video_p99_ms = std::nan("");
  // Haptel's round trip in hops (one host: both ends read the same monotonic
  // clock): the command's way out (sent -> the vehicle's reader took it), and
  // the way back (the state's stamp, its control tick -> the operator's reader).
  double out_p50_ms = std::nan(""), out_p99_ms = std::nan("");
  double back_p50_ms = std::nan(""), back_p99_ms = std::nan("");
};

RttFigures Figures(const Histogram& h) {
  return {h.Percentile(0.5) * 1e-3, h.Percentile(0.99) * 1e-3, h.Count()};
}

/// Waits up to `timeout_s` for `ready`.
template <typename Ready>
bool WaitFor(Ready ready, double timeout_s) {
  const int64_t until = MonotonicNs() + SToNs(timeout_s);
  while (MonotonicNs() < until) {
    if (ready()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return ready();
}

/// Calls `send` (with the time) at kRateHz for `seconds`; after the first
/// second, which warms both ends up, calls `warmed_up` once (to forget what
/// was measured so far).
void Paced(double seconds, const std::function<void()>& warmed_up,
           const std::function<void(int64_t)>& send) {
  const auto period = static_cast<int64_t>(1e9 / kRateHz);
  int64_t next = MonotonicNs();
  const int64_t end = next + SToNs(seconds);
  const int64_t counted_from = next + SToNs(1.0);
  bool counted = false;
  while (MonotonicNs() < end) {
    SleepUntilNs(next);
    next += period;
    const int64_t now = MonotonicNs();
    if (!counted && now >= counted_from) {
      warmed_up();
      counted = true;
    }
    send(now);
  }
}

/// The raw ping-pong: pings at kRateHz for `seconds` to an echo process.
RttFigures RawPingPong(int domain, double seconds) {
  ChildProcess echo((ProgramDirectory() / "haptel-bench").string(),
                    {"link", "--echo", "--domain", std::to_string(domain)});
  LinkConfig config;
  config.domain_id = domain;
  link::Participant participant(config, "haptel-bench-ping");
  Histogram rtt(10.0, 200000);
  link::TreadCommandReader pongs(
      participant, "bench/pong", link::Profile::kCommand, [&](const msg::TreadCommand& c) {
        if (c.sent_ns() != 0) rtt.Record(static_cast<double>(MonotonicNs() - c.sent_ns()) * 1e-3);
      });
  link::TreadCommandWriter pings(participant, "bench/ping", link::Profile::kCommand);
  if (!WaitFor([&] { return pings.matched() > 0 && pongs.matched() > 0; }, 15.0)) {
    throw std::runtime_error("the echo process did not answer");
  }
  msg::TreadCommand m;
  uint64_t seq = 0;
  Paced(
      seconds, [&] { rtt.Reset(); },
      [&](int64_t now) {
        m.seq(++seq);
        m.sent_ns(now);
        pings.Write(m);
      });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  return Figures(rtt);
}

/// Haptel's command round trip to a spawned haptel-vehicle at kRateHz, and
/// its video's latency (decoded, as the view shows it); secured with the
/// folder `security` when it is not empty.
RttFigures HaptelRoundTrip(int domain, double seconds, const std::filesystem::path& security) {
  mediator::VehicleLinkOptions options;
  options.vehicle = LoadVehicle(ShippedFile("config/vehicles/sim-robot.yaml"));
  options.link.domain_id = domain;
  options.link.security = security;
  options.track_file = ShippedFile("config/tracks/test-short.yaml");
  options.program = ProgramDirectory() / "haptel-vehicle";
  options.decode_video = true;
  mediator::VehicleLink vehicle(options);
  if (!WaitFor([&] { return vehicle.last_received_ns() != 0; }, 20.0)) {
    throw std::runtime_error("the vehicle did not answer");
  }
  int tick = 0;
  Histogram out(10.0, 200000), back(10.0, 200000);
  uint64_t last_echo = 0;
  const auto hops = [&] {
    for (const auto& e : vehicle.channel<link::RobotMessages>().inbox().Drain()) {
      const msg::VehicleState& s = e.state;
      if (s.last_command_seq() == 0 || s.last_command_seq() == last_echo) continue;
      last_echo = s.last_command_seq();
      const int64_t taken_ns = s.stamp_ns() - s.last_command_age_ns();
      out.Record(static_cast<double>(taken_ns - s.last_command_sent_ns()) * 1e-3);
      back.Record(static_cast<double>(e.received_ns - s.stamp_ns()) * 1e-3);
    }
  };
  Paced(
      seconds,
      [&] {
        vehicle.ResetRtt();
        out.Reset();
        back.Reset();
      },
      [&](int64_t) {
        // A gentle back-and-forth, so the robot stays near where it started.
        const double v = 0.2 * std::sin(++tick * 0.02);
        vehicle.Send(TreadCommand{v, v});
        hops();
      });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  hops();
  RttFigures figures = Figures(vehicle.Rtt());
  figures.out_p50_ms = out.Percentile(0.5) * 1e-3;
  figures.out_p99_ms = out.Percentile(0.99) * 1e-3;
  figures.back_p50_ms = back.Percentile(0.5) * 1e-3;
  figures.back_p99_ms = back.Percentile(0.99) * 1e-3;
  const video::VideoStats video = vehicle.video().Stats();
  figures.video_p50_ms = video.latency_ms_p50;
  figures.video_p99_ms = video.latency_ms_p99;
  vehicle.Stop();
  return figures;
}

struct LapRow {
  double delay_ms = 0.0;
  double loss_percent = 0.0;
  bool predict = false;
  double prediction_error_m_p95 = std::nan("");
  bool ran = false;
  bool completed = false;
  std::string outcome;
  double lap_time_s = std::nan("");
  int obstacles = 0;
  int gates_passed = 0;
  int gates_total = 0;
  double rtt_p50_ms = std::nan("");
  double wall_s = 0.0;
};

LapRow Lap(const std::filesystem::path& dir, const std::string& track, int domain, double delay_ms,
           double loss_percent, bool predict, const std::string& profile) {
  LapRow row;
  row.delay_ms = delay_ms;
  row.loss_percent = loss_percent;
  row.predict = predict;
  char fault[96];
  std::snprintf(fault, sizeof fault, "delay=%gms,loss=%g%%", delay_ms, loss_percent);
  const std::string db = (dir / "link.db").string();
  std::vector<std::string> words{"run",
                                 "--operator",
                                 "auto",
                                 "--view",
                                 "none",
                                 "--link-fault",
                                 fault,
                                 "--track",
                                 track,
                                 "--json",
                                 "--quiet",
                                 "--domain",
                                 std::to_string(domain),
                                 "--database",
                                 db,
                                 "--vehicle-timeout",
                                 "5",
                                 "--predict",
                                 predict ? "on" : "off"};
  // The profile's rate, queue and jitter; the sweep's delay and loss replace its own.
  if (!profile.empty()) words.insert(words.end(), {"--link-profile", profile});
  const int64_t start = MonotonicNs();
  ChildProcess run((ProgramDirectory() / "haptel").string(), words, ChildProcess::Options{true});
  run.Wait(1800.0);
  row.wall_s = NsToS(MonotonicNs() - start);
  const std::string json = run.LastLine();
  if (json.empty() || json.front() != '{') {
    std::fprintf(stderr, "haptel bench link: the lap at %s gave no result: %s\n", fault,
                 run.err().c_str());
    return row;
  }
  row.ran = true;
  row.completed = JsonFieldOf(json, "completed") == "true";
  row.outcome = JsonFieldOf(json, "outcome");
  row.lap_time_s = Number(json, "lap_time_s");
  row.obstacles = static_cast<int>(Number(json, "obstacles_touched"));
  row.gates_passed = static_cast<int>(Number(json, "gates_passed"));
  row.gates_total = static_cast<int>(Number(json, "gates_total"));
  row.rtt_p50_ms = Number(json, "command_rtt_ms_p50");
  row.prediction_error_m_p95 = Number(json, "prediction_error_m_p95");
  return row;
}

}  // namespace

int BenchLinkMain(int argc, const char* const* argv) {
  bool json = false, smoke = false, rtt_only = false;
  double seconds = 10.0;
  std::string track = ShippedFile("config/tracks/grand-prix.yaml").string();
  std::vector<double> delays{0, 50, 100, 200, 400, 800};
  std::vector<double> losses{0, 5};
  std::vector<bool> predicts{false, true};
  // Domains of the bench's own, away from a default installation's 0.
  int domain = 200 + static_cast<int>(getpid() % 30);
  std::optional<int> lap_domain;
  std::string profile;  // --link-profile: every lap on that link
  try {
    const Args args(
        argc, argv,
        {"seconds", "track", "delays", "losses", "domain", "lap-domain", "predict", "link-profile"},
        {"json", "echo", "rtt-only", kSmokeFlag});
    if (args.Flag("echo")) return Echo(args.Int("domain", 0, 232).value_or(0));
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    rtt_only = args.Flag("rtt-only");  // the round trips alone, no laps
    if (smoke) {  // every part once: the shortest round trips, one lap of the short track, no fault
      seconds = 2.0;
      track = ShippedFile("config/tracks/test-short.yaml").string();
      delays = {0};
      losses = {0};
      predicts = {true};  // the predictor's path, the one a change is likelier to break
    }
    seconds = args.Number("seconds", 2.0, 600.0).value_or(seconds);
    track = args.Value("track").value_or(track);
    domain = args.Int("domain", 0, 231).value_or(domain);  // the laps default to the next one
    lap_domain = args.Int("lap-domain", 0, 232);
    if (auto d = args.Value("delays")) delays = ParseList("delays", *d);
    if (rtt_only) delays.clear();
    if (auto l = args.Value("losses")) losses = ParseList("losses", *l);
    if (auto p = args.Value("predict")) {
      if (*p == "off") {
        predicts = {false};
      } else if (*p == "on") {
        predicts = {true};
      } else if (*p == "both") {
        predicts = {false, true};
      } else {
        throw UsageError("option --predict: expected off, on or both, got '" + *p + "'");
      }
    }
    for (const double l : losses) {
      if (l > 99.0) throw UsageError("option --losses: expected percentages below 100");
    }
    if (auto p = args.Value("link-profile")) {
      LinkFaultFromOptions(*p, std::nullopt,
                           {});  // an unknown profile is refused now, not by every lap
      profile = *p;
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench link: %s\n", e.what());
    return 2;
  }
  const auto dir = OutputDir(smoke);
  PrintSmokeNote("link", smoke, "%.0f s per round trip, %zu lap(s) on %s", seconds,
                 delays.size() * losses.size() * predicts.size(),
                 std::filesystem::path(track).filename().c_str());
  std::printf("haptel bench link: round trip at %.0f Hz for %.0f s, then laps on %s\n\n", kRateHz,
              seconds, track.c_str());

  RttFigures raw, haptel, secured;
  bool rtt_ok = true;
  try {
    raw = RawPingPong(domain, seconds);
    haptel = HaptelRoundTrip(domain, seconds, {});
    // The cost of DDS Security: the same, authenticated and encrypted.
    const std::filesystem::path security = dir / "security";
    if (!std::filesystem::exists(security / "ca.pem"))
      link::InitSecurity(security, {"robot1"}, 365);
    secured = HaptelRoundTrip(domain, seconds, security);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench link: round trip: %s\n", e.what());
    rtt_ok = false;
  }
  const double ratio = raw.p50_ms > 0.0 ? haptel.p50_ms / raw.p50_ms : std::nan("");
  const double p99_ratio = raw.p99_ms > 0.0 ? haptel.p99_ms / raw.p99_ms : std::nan("");
  std::printf("  round trip                   p50 ms   p99 ms   samples   video p50 ms   p99 ms\n");
  const auto print = [](const char* name, const RttFigures& f) {
    std::printf("  %-26s %7.3f  %7.3f   %7llu   %12.2f  %7.2f\n", name, f.p50_ms, f.p99_ms,
                static_cast<unsigned long long>(f.samples), f.video_p50_ms, f.video_p99_ms);
  };
  print("raw Fast DDS ping-pong", raw);
  print("haptel command -> state", haptel);
  print("haptel, DDS Security", secured);
  std::printf(
      "  ratio haptel to raw: p50 %.2f, p99 %.2f (target <= 2 each); security costs %+.3f ms of "
      "round "
      "trip, %+.2f ms of video latency (p50)\n",
      ratio, p99_ratio, secured.p50_ms - haptel.p50_ms, secured.video_p50_ms - haptel.video_p50_ms);
  std::printf(
      "  haptel's round trip in hops, p50 / p99 ms: command out %.3f / %.3f, state back (from its "
      "stamp) "
      "%.3f / %.3f\n\n",
      haptel.out_p50_ms, haptel.out_p99_ms, haptel.back_p50_ms, haptel.back_p99_ms);
  {
    std::ofstream csv(dir / "link_rtt.csv");
    csv << "path,p50_ms,p99_ms,samples,video_p50_ms,video_p99_ms,out_p50_ms,out_p99_ms,back_p50_ms,"
           "back_p99_ms\n";
    for (const auto& [name, f] :
         {std::pair{"raw", raw}, std::pair{"haptel", haptel}, std::pair{"secured", secured}}) {
      csv << name << "," << f.p50_ms << "," << f.p99_ms << "," << f.samples << "," << f.video_p50_ms
          << "," << f.video_p99_ms << "," << f.out_p50_ms << "," << f.out_p99_ms << ","
          << f.back_p50_ms << "," << f.back_p99_ms << "\n";
    }
  }

  std::vector<LapRow> rows;
  std::printf(
      "  delay ms  loss %%  predict  outcome         lap s   x 0 ms  gates  obstacles  rtt p50 ms  "
      "pred. err p95 mm  wall s\n");
  for (const double loss : losses) {
    for (const bool predict : predicts) {
      double lap_at_zero = std::nan("");
      for (const double delay : delays) {
        const LapRow row =
            Lap(dir, track, lap_domain.value_or(domain + 1), delay, loss, predict, profile);
        rows.push_back(row);
        if (delay == 0.0 && row.completed) lap_at_zero = row.lap_time_s;
        std::printf(
            "  %8.0f  %6.1f  %-7s  %-14s %6.2f  %6.2f   %d/%d   %9d  %10.2f  %16.1f  %6.1f\n",
            delay, loss, predict ? "on" : "off", row.ran ? row.outcome.c_str() : "no result",
            row.lap_time_s, row.completed ? row.lap_time_s / lap_at_zero : std::nan(""),
            row.gates_passed, row.gates_total, row.obstacles, row.rtt_p50_ms,
            row.prediction_error_m_p95 * 1e3, row.wall_s);
        std::fflush(stdout);
      }
    }
  }
  {
    std::ofstream csv(dir / "link_laps.csv");
    csv << "delay_ms,loss_percent,predict,outcome,completed,lap_time_s,gates_passed,gates_total,"
           "obstacles,"
           "rtt_p50_ms,prediction_error_m_p95\n";
    for (const LapRow& r : rows) {
      csv << r.delay_ms << "," << r.loss_percent << "," << (r.predict ? 1 : 0) << "," << r.outcome
          << "," << (r.completed ? 1 : 0) << "," << r.lap_time_s << "," << r.gates_passed << ","
          << r.gates_total << "," << r.obstacles << "," << r.rtt_p50_ms << ","
          << r.prediction_error_m_p95 << "\n";
    }
  }
  std::vector<Series> series;
  for (const double loss : losses) {
    for (const bool predict : predicts) {
      Series s;
      char name[64];
      std::snprintf(name, sizeof name, "%g%% loss, prediction %s", loss, predict ? "on" : "off");
      s.name = name;
      for (const LapRow& r : rows) {
        if (r.loss_percent != loss || r.predict != predict || !r.completed) continue;
        s.x.push_back(r.delay_ms);
        s.y.push_back(r.lap_time_s);
      }
      if (!s.x.empty()) series.push_back(s);
    }
  }
  if (!series.empty()) {
    PlotLines(dir / "link_laps.png", series,
              {"The automatic operator's lap against the link's delay (each way)",
               "delay each way, ms", "lap time, s (completed laps)"});
  }
  const bool all_ran = std::all_of(rows.begin(), rows.end(), [](const LapRow& r) { return r.ran; });
  std::printf("\n  wrote %s/link_{rtt,laps}.csv, link_laps.png\n", dir.c_str());
  if (json) {
    std::ostringstream o;
    o << "{\"rtt\":{\"raw_p50_ms\":" << JsonNumber(raw.p50_ms)
      << ",\"raw_p99_ms\":" << JsonNumber(raw.p99_ms)
      << ",\"haptel_p50_ms\":" << JsonNumber(haptel.p50_ms)
      << ",\"haptel_p99_ms\":" << JsonNumber(haptel.p99_ms)
      << ",\"p50_ratio\":" << JsonNumber(ratio)
      << ",\"within_2x\":" << (ratio <= 2.0 ? "true" : "false")
      << ",\"p99_ratio\":" << JsonNumber(p99_ratio)
      << ",\"p99_within_2x\":" << (p99_ratio <= 2.0 ? "true" : "false")
      << ",\"out_p50_ms\":" << JsonNumber(haptel.out_p50_ms)
      << ",\"out_p99_ms\":" << JsonNumber(haptel.out_p99_ms)
      << ",\"back_p50_ms\":" << JsonNumber(haptel.back_p50_ms)
      << ",\"back_p99_ms\":" << JsonNumber(haptel.back_p99_ms)
      << ",\"secured_p50_ms\":" << JsonNumber(secured.p50_ms)
      << ",\"secured_p99_ms\":" << JsonNumber(secured.p99_ms)
      << ",\"video_p50_ms\":" << JsonNumber(haptel.video_p50_ms)
      << ",\"secured_video_p50_ms\":" << JsonNumber(secured.video_p50_ms) << "},\"laps\":[";
    for (size_t i = 0; i < rows.size(); ++i) {
      const LapRow& r = rows[i];
      o << (i ? "," : "") << "{\"delay_ms\":" << JsonNumber(r.delay_ms)
        << ",\"loss_percent\":" << JsonNumber(r.loss_percent)
        << ",\"outcome\":" << JsonString(r.outcome)
        << ",\"predict\":" << (r.predict ? "true" : "false") << ",\"prediction_error_m_p95\":"
        << (std::isfinite(r.prediction_error_m_p95) ? JsonNumber(r.prediction_error_m_p95)
                                                    : std::string("null"))
        << ",\"completed\":" << (r.completed ? "true" : "false")
        << ",\"lap_time_s\":" << JsonNumber(std::isfinite(r.lap_time_s) ? r.lap_time_s : -1.0)
        << ",\"obstacles\":" << r.obstacles
        << ",\"rtt_p50_ms\":" << JsonNumber(std::isfinite(r.rtt_p50_ms) ? r.rtt_p50_ms : -1.0)
        << "}";
    }
    o << "]}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return rtt_ok && all_ran ? 0 : 1;
}

}  // namespace haptel::bench
