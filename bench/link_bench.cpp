#include "link_bench.hpp"

#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "haptel/config/link.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/reality.hpp"
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
#include "haptel/record/truth_record.hpp"
#include "haptel/study/statistics.hpp"
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

/// --seeds: reality seeds as a list of numbers and ranges, "1-5" or "1,3,7-9".
std::vector<int> ParseSeeds(const std::string& text) {
  std::vector<int> out;
  const auto bad = [&]() {
    return UsageError(
        "option --seeds: expected seeds (0 to 2147483647) and ranges like 1-5, got '" + text + "'");
  };
  for (const std::string& item : SplitList(text)) {
    const auto dash = item.find('-', 1);
    try {
      size_t used = 0;
      const long first = std::stol(item.substr(0, dash), &used);
      if (used != item.substr(0, dash).size()) throw bad();
      long last = first;
      if (dash != std::string::npos) {
        last = std::stol(item.substr(dash + 1), &used);
        if (used != item.size() - dash - 1) throw bad();
      }
      if (first < 0 || last < first || last > 2147483647L || last - first > 1000) throw bad();
      for (long seed = first; seed <= last; ++seed) {
        if (std::find(out.begin(), out.end(), seed) == out.end())
          out.push_back(static_cast<int>(seed));
      }
    } catch (const std::logic_error&) {  // stol's invalid_argument, out_of_range
      throw bad();
    }
  }
  if (out.empty()) throw bad();
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

/// Decoded frames the video's latency is taken over, at the least.
constexpr uint64_t kVideoFramesMeasured = 10;

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
  // The video's latency needs decoded frames. The vehicle's camera thread is
  // niced (it yields to the vehicle's control), so on a loaded host it may
  // not have sent a key frame within a short window (CI's suite: none in the
  // smoke's 2 s): the figure waits for a few, not for the clock.
  WaitFor([&] { return vehicle.video().Stats().frames >= kVideoFramesMeasured; }, 30.0);
  const video::VideoStats video = vehicle.video().Stats();
  figures.video_p50_ms = video.latency_ms_p50;
  figures.video_p99_ms = video.latency_ms_p99;
  vehicle.Stop();
  return figures;
}

/// How the operator side predicts (`haptel run --predict`): not at all, with
/// the vehicle's nominal model only, or learning the vehicle it drives.
enum class PredictMode { kOff, kNominal, kLearn };

const char* ModeName(PredictMode mode) {
  switch (mode) {
    case PredictMode::kOff:
      return "off";
    case PredictMode::kNominal:
      return "nominal";
    case PredictMode::kLearn:
      return "learn";
  }
  return "?";
}

/// --predict: a list of off, nominal, learn (on = learn); `both` (off and
/// on) and `all` (the three) as before.
std::vector<PredictMode> ParseModes(const std::string& text) {
  std::vector<PredictMode> out;
  const auto add = [&](PredictMode m) {
    if (std::find(out.begin(), out.end(), m) == out.end()) out.push_back(m);
  };
  for (const std::string& item : SplitList(text)) {
    if (item == "off") {
      add(PredictMode::kOff);
    } else if (item == "nominal") {
      add(PredictMode::kNominal);
    } else if (item == "on" || item == "learn") {
      add(PredictMode::kLearn);
    } else if (item == "both") {
      add(PredictMode::kOff);
      add(PredictMode::kLearn);
    } else if (item == "all") {
      add(PredictMode::kOff);
      add(PredictMode::kNominal);
      add(PredictMode::kLearn);
    } else {
      throw UsageError(
          "option --predict: expected off, nominal, learn (or on), both or all, got '" + item +
          "'");
    }
  }
  if (out.empty()) throw UsageError("option --predict: expected at least one mode");
  return out;
}

std::string JoinModes(const std::vector<PredictMode>& modes) {
  std::vector<std::string> names;
  for (const PredictMode m : modes) names.push_back(ModeName(m));
  return JoinList(names);
}

std::string JoinNumbers(const std::vector<double>& values) {
  std::vector<std::string> texts;
  for (const double v : values) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    texts.push_back(text);
  }
  return JoinList(texts);
}

/// A vehicle the laps are driven with: its name in the tables and the
/// `haptel run` options that pick it and its track.
struct LapVehicle {
  std::string name;
  std::vector<std::string> words;
};

/// One lap of the sweep: which vehicle, in which reality, predicted how,
/// over which link.
struct LapSpec {
  const LapVehicle* vehicle = nullptr;
  std::string reality;  ///< a name (config/realities/NAME.yaml) or a file
  PredictMode mode = PredictMode::kOff;
  double delay_ms = 0.0;
  double loss_percent = 0.0;
  std::optional<int> seed;  ///< the reality's draws (none: the reality file's seed)
};

/// The `haptel run` options of a lap's reality, prediction and link fault:
/// the one place the sweep's dimensions become the run's options.
std::vector<std::string> LapOptions(const LapSpec& spec, const std::string& profile) {
  char fault[96];
  std::snprintf(fault, sizeof fault, "delay=%gms,loss=%g%%", spec.delay_ms, spec.loss_percent);
  std::vector<std::string> words{"--link-fault",      fault,       "--predict",
                                 ModeName(spec.mode), "--reality", spec.reality};
  if (spec.seed) words.insert(words.end(), {"--reality-seed", std::to_string(*spec.seed)});
  // The profile's rate, queue and jitter; the sweep's delay and loss replace its own.
  if (!profile.empty()) words.insert(words.end(), {"--link-profile", profile});
  return words;
}

/// A parameter the predictor estimated, beside the vehicle's truth.
struct Estimate {
  std::string param;
  double estimate = std::nan("");
  double truth = std::nan("");
  double known_s = std::nan("");  ///< when the estimator first held it known (its sd under 2 %)
};

struct LapRow {
  LapSpec spec;
  std::string reality;  ///< as the run names it (from the truth record)
  std::string seed;
  bool ran = false;
  bool completed = false;
  std::string outcome;
  /// The lap as judged from where the vehicle truly went, where its truth
  /// record judged it (`judged_on_truth`); else the live lap's (its odometry's).
  double lap_time_s = std::nan("");
  bool judged_on_truth = false;
  double lap_time_live_s = std::nan("");  ///< the live lap's, judged from the odometry
  int gates_passed_live = 0;
  double ratio_to_0ms = std::nan("");  ///< to the 0 ms lap of the same vehicle, reality, loss, mode
  int obstacles = 0;
  int gates_passed = 0;
  int gates_total = 0;
  double rtt_p50_ms = std::nan("");
  /// The prediction against the truth in the map's frame (the headline:
  /// prediction_score.hpp), and against the raw truth in the world's.
  double error_m_p50 = std::nan("");
  double error_m_p95 = std::nan("");
  double error_world_m_p95 = std::nan("");
  double odometry_error_m_p95 = std::nan("");  ///< against the vehicle's own (reported) states
  /// The robot's pose at each state's moment against the truth: as the run
  /// took it (localised on the track, or its odometry), and its odometry's.
  double pose_error_m_p95 = std::nan("");
  double pose_error_world_m_p95 = std::nan("");
  double odometry_truth_error_m_p95 = std::nan("");
  /// The localiser's map against the track as built (map's frame, RMS m):
  /// as learnt, and as the file has it (the run's estimated_map).
  double map_learnt_m_rms = std::nan("");
  double map_file_m_rms = std::nan("");
  /// When every estimated parameter was known (the last one's known_s), s
  /// since the session started; NaN when one never was.
  double converged_s = std::nan("");
  std::vector<Estimate> estimated;
  std::vector<TruthRow> path;  ///< where the vehicle truly was (its truth record)
  double path_gap_m_mean =
      std::nan("");  ///< from the `none` reality's path (same vehicle, mode, link)
  double path_gap_m_max = std::nan("");
  double wall_s = 0.0;
};

/// The text of `{…}` that follows `"key":` in a one-line JSON object; "" when
/// absent or not an object.
std::string JsonObjectOf(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\":{";
  const auto at = json.find(needle);
  if (at == std::string::npos) return "";
  const size_t start = at + needle.size() - 1;
  int depth = 0;
  bool in_string = false;
  for (size_t i = start; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{') {
      ++depth;
    } else if (c == '}' && --depth == 0) {
      return json.substr(start, i - start + 1);
    }
  }
  return "";
}

/// The keys of a JSON object's members whose values are objects, in order.
std::vector<std::string> ObjectMemberKeys(const std::string& object) {
  std::vector<std::string> keys;
  size_t at = 0;
  while ((at = object.find("\":{", at)) != std::string::npos) {
    const auto open = object.rfind('"', at - 1);
    if (open == std::string::npos) break;
    const std::string key = object.substr(open + 1, at - open - 1);
    const std::string inner = JsonObjectOf(object, key);
    keys.push_back(key);
    at += inner.size() + 3;
  }
  return keys;
}

/// Distance from (x, y) to the polyline `path` (its nearest segment).
double DistanceToPath(double x, double y, const std::vector<TruthRow>& path) {
  double best = INFINITY;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const double ax = path[i].x, ay = path[i].y;
    const double dx = path[i + 1].x - ax, dy = path[i + 1].y - ay;
    const double len2 = dx * dx + dy * dy;
    const double t =
        len2 > 0.0 ? std::clamp(((x - ax) * dx + (y - ay) * dy) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(x - (ax + t * dx), y - (ay + t * dy)));
  }
  if (path.size() == 1) best = std::hypot(x - path[0].x, y - path[0].y);
  return best;
}

/// How far apart two driven paths are: the mean and the largest distance
/// from a point of either to the other (the symmetric Hausdorff distance).
std::pair<double, double> PathGap(const std::vector<TruthRow>& a, const std::vector<TruthRow>& b) {
  if (a.empty() || b.empty()) return {std::nan(""), std::nan("")};
  double sum = 0.0, most = 0.0;
  size_t n = 0;
  for (const auto& [from, to] : {std::pair{&a, &b}, std::pair{&b, &a}}) {
    for (const TruthRow& p : *from) {
      const double d = DistanceToPath(p.x, p.y, *to);
      sum += d;
      most = std::max(most, d);
      ++n;
    }
  }
  return {sum / static_cast<double>(n), most};
}

/// Runs one lap (`haptel run` with the automatic operator, no view) and
/// reads its JSON line, and the vehicle's true path from its truth record
/// (kept in `truth`).
LapRow Lap(const std::filesystem::path& db, const std::filesystem::path& truth, int domain,
           const LapSpec& spec, const std::string& profile) {
  LapRow row;
  row.spec = spec;
  std::filesystem::remove(truth);
  std::vector<std::string> words{"run",        "--operator", "auto",
                                 "--view",     "none",       "--json",
                                 "--quiet",    "--domain",   std::to_string(domain),
                                 "--database", db.string(),  "--vehicle-timeout",
                                 "5",          "--truth",    truth.string()};
  words.insert(words.end(), spec.vehicle->words.begin(), spec.vehicle->words.end());
  const std::vector<std::string> options = LapOptions(spec, profile);
  words.insert(words.end(), options.begin(), options.end());
  const int64_t start = MonotonicNs();
  ChildProcess run((ProgramDirectory() / "haptel").string(), words, ChildProcess::Options{true});
  run.Wait(1800.0);
  row.wall_s = NsToS(MonotonicNs() - start);
  const std::string json = run.LastLine();
  if (json.empty() || json.front() != '{') {
    std::fprintf(stderr, "haptel bench link: the %s lap (%s, predict %s, %s) gave no result: %s\n",
                 spec.vehicle->name.c_str(), spec.reality.c_str(), ModeName(spec.mode),
                 options[1].c_str(), run.err().c_str());
    return row;
  }
  row.ran = true;
  row.completed = JsonFieldOf(json, "completed") == "true";
  row.outcome = JsonFieldOf(json, "outcome");
  row.lap_time_s = Number(json, "lap_time_s");
  row.obstacles = static_cast<int>(Number(json, "obstacles_touched"));
  row.gates_passed = static_cast<int>(Number(json, "gates_passed"));
  row.gates_total = static_cast<int>(Number(json, "gates_total"));
  // A real vehicle's lap is judged from its odometry, which may pass a gate
  // the vehicle truly missed: where the truth judged it, that is the lap.
  row.lap_time_live_s = row.lap_time_s;
  row.gates_passed_live = row.gates_passed;
  if (const std::string truth = JsonFieldOf(json, "completed_truth");
      truth == "true" || truth == "false") {
    row.judged_on_truth = true;
    row.completed = row.completed && truth == "true";
    row.lap_time_s = Number(json, "lap_time_truth_s");
    row.gates_passed = static_cast<int>(Number(json, "gates_truth_passed"));
  }
  row.rtt_p50_ms = Number(json, "command_rtt_ms_p50");
  row.error_m_p50 = Number(json, "prediction_error_m_p50");
  row.error_m_p95 = Number(json, "prediction_error_m_p95");
  row.error_world_m_p95 = Number(json, "prediction_error_world_m_p95");
  row.odometry_error_m_p95 = Number(json, "prediction_error_odometry_m_p95");
  row.pose_error_m_p95 = Number(json, "localisation_error_m_p95");
  row.pose_error_world_m_p95 = Number(json, "localisation_error_world_m_p95");
  row.odometry_truth_error_m_p95 = Number(json, "odometry_error_m_p95");
  if (const std::string map = JsonObjectOf(json, "estimated_map"); !map.empty()) {
    row.map_learnt_m_rms = Number(map, "learnt_m_rms");
    row.map_file_m_rms = Number(map, "file_m_rms");
  }
  const std::string reality = JsonObjectOf(json, "reality");
  row.reality = reality.empty() ? spec.reality : JsonFieldOf(reality, "name");
  row.seed = JsonFieldOf(reality, "seed");
  const std::string estimated = JsonObjectOf(json, "estimated");
  for (const std::string& param : ObjectMemberKeys(estimated)) {
    const std::string e = JsonObjectOf(estimated, param);
    row.estimated.push_back(
        {param, Number(e, "estimate"), Number(e, "truth"), Number(e, "known_s")});
  }
  bool all_known = !row.estimated.empty();
  double last_known_s = 0.0;
  for (const Estimate& e : row.estimated) {
    all_known = all_known && std::isfinite(e.known_s);
    if (all_known) last_known_s = std::max(last_known_s, e.known_s);
  }
  if (all_known) row.converged_s = last_known_s;
  try {
    // Every 5th row (the control rate's 0.01 s or so): paths a few centimetres a point.
    const record::TruthRecord record = record::TruthRecord::Load(truth);
    for (size_t i = 0; i < record.rows().size(); i += 5) row.path.push_back(record.rows()[i]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench link: the lap's truth: %s\n", e.what());
  }
  return row;
}

/// A figure for a table: "-" when there is none.
std::string Cell(double v, double scale = 1.0, const char* format = "%.1f") {
  if (!std::isfinite(v)) return "-";
  char text[32];
  std::snprintf(text, sizeof text, format, v * scale);
  return text;
}

std::string JsonOrNull(double v) { return std::isfinite(v) ? JsonNumber(v) : std::string("null"); }

/// The targets, judged on the sweep's laps (NaN / unknown where the
/// sweep has no lap to judge them by).
struct Targets {
  // lab: the 400 ms lap learning within 1.3x the 0 ms lap, its error p95 within 5 cm.
  double lab_ratio_400ms = std::nan("");
  double lab_error_m_p95_400ms = std::nan("");        ///< the map's frame: what is judged
  double lab_error_world_m_p95_400ms = std::nan("");  ///< the world's, beside it
  // harsh: every learning lap completed, and learning better than the
  // nominal model (a lower error p95) at every delay.
  std::optional<bool> harsh_completed;
  std::optional<bool> harsh_learn_beats_nominal;
  // harsh over two seeds or more: learning better than the nominal model in
  // every cell (lap and error p95 at each delay): the paired difference
  // learn − nominal's 95 % interval below 0.
  std::optional<bool> harsh_learn_better_every_cell;
  // none: the twin's error, which must stay ~0 (the scoring's own check).
  double none_error_m_p95_max = std::nan("");

  std::optional<bool> LabRatioMet() const {
    if (!std::isfinite(lab_ratio_400ms)) return std::nullopt;
    return lab_ratio_400ms <= 1.3;
  }
  std::optional<bool> LabErrorMet() const {
    if (!std::isfinite(lab_error_m_p95_400ms)) return std::nullopt;
    return lab_error_m_p95_400ms <= 0.05;
  }
};

/// Mean, spread and the mean's 95 % interval of per-seed figures (Student's
/// t with n − 1 degrees of freedom: the seeds are few, their spread unknown).
struct OverSeeds {
  size_t n = 0;
  double mean = std::nan("");
  double sd = std::nan("");  ///< the sample standard deviation (n − 1)
  double ci_low = std::nan("");
  double ci_high = std::nan("");
};

OverSeeds Summarise(const std::vector<double>& values) {
  OverSeeds o;
  o.n = values.size();
  if (o.n == 0) return o;
  double sum = 0.0;
  for (const double v : values) sum += v;
  o.mean = sum / static_cast<double>(o.n);
  if (o.n < 2) return o;
  double squares = 0.0;
  for (const double v : values) squares += (v - o.mean) * (v - o.mean);
  o.sd = std::sqrt(squares / static_cast<double>(o.n - 1));
  const double half = study::StudentTQuantile(0.975, static_cast<double>(o.n - 1)) * o.sd /
                      std::sqrt(static_cast<double>(o.n));
  o.ci_low = o.mean - half;
  o.ci_high = o.mean + half;
  return o;
}

/// One cell of the sweep (vehicle, reality, prediction, delay, loss) over its seeds.
struct SweepCell {
  const LapVehicle* vehicle = nullptr;
  std::string reality;
  PredictMode mode = PredictMode::kOff;
  double delay_ms = 0.0;
  double loss_percent = 0.0;
  size_t laps = 0, completed = 0;
  OverSeeds lap_time_s, error_m_p50, error_m_p95;
};

bool SameCell(const LapSpec& a, const LapSpec& b) {
  return a.vehicle == b.vehicle && a.reality == b.reality && a.mode == b.mode &&
         a.delay_ms == b.delay_ms && a.loss_percent == b.loss_percent;
}

std::vector<SweepCell> SweepCells(const std::vector<LapRow>& rows) {
  std::vector<SweepCell> cells;
  std::vector<bool> done(rows.size(), false);
  for (size_t i = 0; i < rows.size(); ++i) {
    if (done[i]) continue;
    const LapSpec& spec = rows[i].spec;
    SweepCell c;
    c.vehicle = spec.vehicle;
    c.reality = spec.reality;
    c.mode = spec.mode;
    c.delay_ms = spec.delay_ms;
    c.loss_percent = spec.loss_percent;
    std::vector<double> laps, p50, p95;
    for (size_t k = i; k < rows.size(); ++k) {
      if (done[k] || !SameCell(rows[k].spec, spec)) continue;
      done[k] = true;
      const LapRow& r = rows[k];
      ++c.laps;
      if (r.completed) {
        ++c.completed;
        laps.push_back(r.lap_time_s);
      }
      if (std::isfinite(r.error_m_p95)) {
        p50.push_back(r.error_m_p50);
        p95.push_back(r.error_m_p95);
      }
    }
    c.lap_time_s = Summarise(laps);
    c.error_m_p50 = Summarise(p50);
    c.error_m_p95 = Summarise(p95);
    cells.push_back(c);
  }
  return cells;
}

/// Learning against the nominal model, seed by seed (the same reality drawn,
/// the same link): the difference learn − nominal of one figure, over the
/// seeds where both laps have it. Negative: learning is better.
struct Paired {
  const LapVehicle* vehicle = nullptr;
  std::string reality;
  double delay_ms = 0.0;
  double loss_percent = 0.0;
  std::string figure;  ///< lap_time_s | prediction_error_m_p95
  OverSeeds difference;

  /// "better" / "worse" when the interval excludes 0, else "no difference shown".
  const char* Verdict() const {
    if (difference.n < 2) return "one seed";
    if (difference.ci_high < 0.0) return "better";
    if (difference.ci_low > 0.0) return "worse";
    return "no difference shown";
  }
};

std::vector<Paired> PairLearnWithNominal(const std::vector<LapRow>& rows) {
  std::vector<Paired> out;
  std::vector<bool> done(rows.size(), false);
  for (size_t i = 0; i < rows.size(); ++i) {
    if (done[i] || rows[i].spec.mode != PredictMode::kLearn) continue;
    const LapSpec& cell = rows[i].spec;
    LapSpec nominal_cell = cell;
    nominal_cell.mode = PredictMode::kNominal;
    std::vector<double> laps, errors;
    for (size_t k = i; k < rows.size(); ++k) {
      if (done[k] || !SameCell(rows[k].spec, cell)) continue;
      done[k] = true;
      const LapRow& learn = rows[k];
      for (const LapRow& nominal : rows) {
        if (!SameCell(nominal.spec, nominal_cell) || nominal.spec.seed != learn.spec.seed) continue;
        if (learn.completed && nominal.completed)
          laps.push_back(learn.lap_time_s - nominal.lap_time_s);
        if (std::isfinite(learn.error_m_p95) && std::isfinite(nominal.error_m_p95))
          errors.push_back(learn.error_m_p95 - nominal.error_m_p95);
      }
    }
    if (laps.empty() && errors.empty()) continue;  // no nominal lap in the sweep
    out.push_back({cell.vehicle, cell.reality, cell.delay_ms, cell.loss_percent, "lap_time_s",
                   Summarise(laps)});
    out.push_back({cell.vehicle, cell.reality, cell.delay_ms, cell.loss_percent,
                   "prediction_error_m_p95", Summarise(errors)});
  }
  return out;
}

/// Judges the robot's laps (the targets are the robot's) at 0 % loss; over
/// several seeds, the lab figures are the seeds' means.
Targets Judge(const std::vector<LapRow>& rows, const std::vector<Paired>& paired) {
  Targets t;
  std::vector<double> lab_ratios, lab_errors, lab_errors_world;
  for (const LapRow& r : rows) {
    if (r.spec.vehicle->name != "robot" || r.spec.loss_percent != 0.0) continue;
    if (r.reality == "lab" && r.spec.mode == PredictMode::kLearn && r.spec.delay_ms == 400.0) {
      lab_ratios.push_back(r.ratio_to_0ms);
      lab_errors.push_back(r.error_m_p95);
      lab_errors_world.push_back(r.error_world_m_p95);
    }
    if (r.reality == "harsh" && r.spec.mode == PredictMode::kLearn) {
      t.harsh_completed = t.harsh_completed.value_or(true) && r.completed;
      for (const LapRow& nominal : rows) {
        LapSpec spec = r.spec;
        spec.mode = PredictMode::kNominal;
        if (!SameCell(nominal.spec, spec) || nominal.spec.seed != r.spec.seed) continue;
        t.harsh_learn_beats_nominal =
            t.harsh_learn_beats_nominal.value_or(true) && r.error_m_p95 < nominal.error_m_p95;
      }
    }
    if (r.reality == "none" && r.spec.mode != PredictMode::kOff && std::isfinite(r.error_m_p95)) {
      t.none_error_m_p95_max = std::isfinite(t.none_error_m_p95_max)
                                   ? std::max(t.none_error_m_p95_max, r.error_m_p95)
                                   : r.error_m_p95;
    }
  }
  if (!lab_ratios.empty()) {
    t.lab_ratio_400ms = Summarise(lab_ratios).mean;
    t.lab_error_m_p95_400ms = Summarise(lab_errors).mean;
    t.lab_error_world_m_p95_400ms = Summarise(lab_errors_world).mean;
  }
  for (const Paired& p : paired) {
    if (p.vehicle->name != "robot" || p.reality != "harsh" || p.loss_percent != 0.0 ||
        p.difference.n < 2)
      continue;
    t.harsh_learn_better_every_cell =
        t.harsh_learn_better_every_cell.value_or(true) && std::string(p.Verdict()) == "better";
  }
  return t;
}

const char* Verdict(const std::optional<bool>& met) {
  return !met ? "not measured" : *met ? "met" : "MISSED";
}

std::string JsonVerdict(const std::optional<bool>& met) {
  return !met ? "null" : *met ? "true" : "false";
}

}  // namespace

int BenchLinkMain(int argc, const char* const* argv) {
  bool json = false, smoke = false, rtt_only = false;
  double seconds = 10.0;
  std::string track = ShippedFile("config/tracks/grand-prix.yaml").string();
  std::string blimp_track = ShippedFile("config/tracks/blimp-hop.yaml").string();
  std::vector<std::string> vehicle_names{"robot", "blimp"};
  std::vector<std::string> realities{"none", "lab", "harsh"};
  std::vector<double> delays{0, 100, 200, 400};
  std::vector<double> losses{0};
  std::vector<PredictMode> modes{PredictMode::kOff, PredictMode::kNominal, PredictMode::kLearn};
  // Domains of the bench's own, away from a default installation's 0.
  int domain = 200 + static_cast<int>(getpid() % 30);
  std::optional<int> lap_domain;
  std::string profile;                                  // --link-profile: every lap on that link
  std::vector<std::optional<int>> seeds{std::nullopt};  // --seeds; none: each reality file's
  bool simulated_time = false;
  try {
    const Args args(argc, argv,
                    {"seconds", "track", "blimp-track", "vehicles", "reality", "delays", "losses",
                     "domain", "lap-domain", "predict", "link-profile", "seeds"},
                    {"json", "echo", "rtt-only", "simulated-time", kSmokeFlag});
    if (args.Flag("echo")) return Echo(args.Int("domain", 0, 232).value_or(0));
    json = args.Flag("json");
    smoke = args.Flag(kSmokeFlag);
    rtt_only = args.Flag("rtt-only");  // the round trips alone, no laps
    if (smoke) {  // every part once: the shortest round trips, one learning lap of the short
                  // track (the predictor's path, the one a change is likelier to break) in the
                  // twin's reality (the quickest lap, its truth record and estimates all the
                  // same), no fault
      seconds = 2.0;
      track = ShippedFile("config/tracks/test-short.yaml").string();
      vehicle_names = {"robot"};
      realities = {"none"};
      delays = {0};
      modes = {PredictMode::kLearn};
    }
    seconds = args.Number("seconds", 2.0, 600.0).value_or(seconds);
    track = args.Value("track").value_or(track);
    blimp_track = args.Value("blimp-track").value_or(blimp_track);
    domain = args.Int("domain", 0, 231).value_or(domain);  // the laps default to the next one
    lap_domain = args.Int("lap-domain", 0, 232);
    if (auto d = args.Value("delays")) delays = ParseList("delays", *d);
    if (rtt_only) delays.clear();
    if (auto l = args.Value("losses")) losses = ParseList("losses", *l);
    if (auto p = args.Value("predict")) modes = ParseModes(*p);
    if (auto v = args.Value("vehicles")) vehicle_names = SplitList(*v);
    for (const std::string& v : vehicle_names) {
      if (v != "robot" && v != "blimp")
        throw UsageError("option --vehicles: expected robot and/or blimp, got '" + v + "'");
    }
    if (vehicle_names.empty()) throw UsageError("option --vehicles: expected robot and/or blimp");
    if (auto r = args.Value("reality")) realities = SplitList(*r);
    if (realities.empty()) throw UsageError("option --reality: expected at least one reality");
    // A missing or bad reality is refused now (naming its file, key and line), not by every lap.
    for (const std::string& r : realities) LoadReality(RealityFile(r));
    for (const double l : losses) {
      if (l > 99.0) throw UsageError("option --losses: expected percentages below 100");
    }
    if (auto p = args.Value("link-profile")) {
      LinkFaultFromOptions(*p, std::nullopt,
                           {});  // an unknown profile is refused now, not by every lap
      profile = *p;
    }
    if (auto s = args.Value("seeds")) {
      const std::vector<int> list = ParseSeeds(*s);
      seeds.assign(list.begin(), list.end());
    }
    simulated_time = args.Flag("simulated-time");
    if (simulated_time) {
      // `haptel run --simulated-time`: the robot stepped in the run's process on one
      // simulated clock, the link its delay alone.
      if (std::find(vehicle_names.begin(), vehicle_names.end(), "blimp") != vehicle_names.end())
        throw UsageError("option --simulated-time: the robot's laps only; add --vehicles robot");
      if (!profile.empty() ||
          std::any_of(losses.begin(), losses.end(), [](double l) { return l > 0.0; }))
        throw UsageError(
            "option --simulated-time: the link's delay alone is simulated; drop --losses and "
            "--link-profile");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "haptel bench link: %s\n", e.what());
    return 2;
  }
  std::vector<LapVehicle> vehicles;
  for (const std::string& name : vehicle_names) {
    if (name == "robot") {
      vehicles.push_back({"robot", {"--track", track}});
      if (simulated_time) vehicles.back().words.push_back("--simulated-time");
    }
    if (name == "blimp") {
      vehicles.push_back(
          {"blimp",
           {"--config", ShippedFile("config/blimp.yaml").string(), "--track", blimp_track}});
    }
  }
  const auto dir = OutputDir(smoke);
  const size_t laps = vehicles.size() * realities.size() * delays.size() * losses.size() *
                      modes.size() * seeds.size();
  PrintSmokeNote("link", smoke, "%.0f s per round trip, %zu lap(s) on %s", seconds, laps,
                 std::filesystem::path(track).filename().c_str());
  std::vector<std::string> seed_names;
  for (const std::optional<int>& seed : seeds)
    seed_names.push_back(seed ? std::to_string(*seed) : "the file's");
  std::printf(
      "haptel bench link: round trip at %.0f Hz for %.0f s, then %zu laps (%s; realities %s, "
      "seeds %s, delays %s ms, prediction %s%s)\n\n",
      kRateHz, seconds, laps, JoinList(vehicle_names).c_str(), JoinList(realities).c_str(),
      JoinList(seed_names).c_str(), JoinNumbers(delays).c_str(), JoinModes(modes).c_str(),
      simulated_time ? "; simulated time" : "");

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

  // ---- the laps: vehicles x realities x losses x modes x delays
  const int laps_domain = lap_domain.value_or(domain + 1);
  const std::filesystem::path db = dir / "link.db";            // the laps' runs
  const std::filesystem::path truth_dir = dir / "link_truth";  // and their vehicles' truth records
  std::filesystem::create_directories(truth_dir);
  std::vector<LapRow> rows;
  for (const LapVehicle& vehicle : vehicles) {
    if (delays.empty()) break;
    std::printf("  [%s]\n", vehicle.name.c_str());
    std::printf(
        "  reality  seed        predict  delay ms  loss %%  outcome         lap s  x 0 ms  gates  "
        "obst.  rtt p50 ms  err p50 mm  err p95 mm  world p95 mm  odom. p95 mm  pose p95 mm  "
        "world p95 mm  odo-truth p95 mm  converged s  gap to none m  wall s\n");
    std::printf(
        "  (err, pose: against the truth in the map's frame; world: against the raw truth)\n");
    for (const std::string& reality : realities) {
      for (const double loss : losses) {
        for (const PredictMode mode : modes) {
          for (const std::optional<int>& seed : seeds) {
            double lap_at_zero = std::nan("");
            for (const double delay : delays) {
              char name[160];
              std::snprintf(name, sizeof name, "%s-%s%s-%s-%gms-%gpc.csv", vehicle.name.c_str(),
                            std::filesystem::path(reality).stem().c_str(),
                            seed ? ("-seed" + std::to_string(*seed)).c_str() : "", ModeName(mode),
                            delay, loss);
              LapRow row = Lap(db, truth_dir / name, laps_domain,
                               {&vehicle, reality, mode, delay, loss, seed}, profile);
              if (delay == 0.0 && row.completed) lap_at_zero = row.lap_time_s;
              if (row.completed) row.ratio_to_0ms = row.lap_time_s / lap_at_zero;
              // The reality gap: this lap's path against the twin's (the same lap in `none`).
              for (const LapRow& twin : rows) {
                if (twin.spec.vehicle == &vehicle && twin.reality == "none" &&
                    twin.spec.mode == mode && twin.spec.delay_ms == delay &&
                    twin.spec.seed == seed && twin.spec.loss_percent == loss && twin.completed &&
                    row.completed) {
                  std::tie(row.path_gap_m_mean, row.path_gap_m_max) = PathGap(row.path, twin.path);
                }
              }
              std::printf(
                  "  %-7s  %-10s  %-7s  %8.0f  %6.1f  %-14s %6.2f  %6s  %2d/%-2d  %5d  %10s  %10s  "
                  "%10s  %12s  %12s  %11s  %12s  %16s  %11s  %13s  %6.1f\n",
                  row.reality.c_str(), row.seed.empty() ? "-" : row.seed.c_str(), ModeName(mode),
                  delay, loss, row.ran ? row.outcome.c_str() : "no result", row.lap_time_s,
                  Cell(row.ratio_to_0ms, 1.0, "%.2f").c_str(), row.gates_passed, row.gates_total,
                  row.obstacles, Cell(row.rtt_p50_ms, 1.0, "%.2f").c_str(),
                  Cell(row.error_m_p50, 1e3).c_str(), Cell(row.error_m_p95, 1e3).c_str(),
                  Cell(row.error_world_m_p95, 1e3).c_str(),
                  Cell(row.odometry_error_m_p95, 1e3).c_str(),
                  Cell(row.pose_error_m_p95, 1e3).c_str(),
                  Cell(row.pose_error_world_m_p95, 1e3).c_str(),
                  Cell(row.odometry_truth_error_m_p95, 1e3).c_str(), Cell(row.converged_s).c_str(),
                  row.path_gap_m_mean >= 0.0 ? (Cell(row.path_gap_m_mean, 1.0, "%.2f") + "/" +
                                                Cell(row.path_gap_m_max, 1.0, "%.2f"))
                                                   .c_str()
                                             : "-",
                  row.wall_s);
              if (!row.estimated.empty()) {
                std::string line = "      estimated (truth, known at s):";
                for (const Estimate& e : row.estimated) {
                  line += " " + e.param + " " + Cell(e.estimate, 1.0, "%.4g") + " (" +
                          Cell(e.truth, 1.0, "%.4g") + ", " + Cell(e.known_s) + ")";
                }
                std::printf("%s\n", line.c_str());
              }
              std::fflush(stdout);
              rows.push_back(std::move(row));
            }
          }
        }
      }
    }
    std::printf("\n");
  }

  // The reality gap at 0 ms: each reality's lap beside the twin's.
  if (!rows.empty()) {
    std::printf("  the 0 ms laps (the reality gap; path gap to none: mean / max m)\n");
    for (const LapRow& r : rows) {
      if (r.spec.delay_ms != 0.0 || r.spec.loss_percent != losses.front()) continue;
      std::printf("    %-6s %-7s predict %-7s  %-14s lap %6.2f s  path gap %s / %s m\n",
                  r.spec.vehicle->name.c_str(), r.reality.c_str(), ModeName(r.spec.mode),
                  r.ran ? r.outcome.c_str() : "no result", r.lap_time_s,
                  Cell(r.path_gap_m_mean, 1.0, "%.3f").c_str(),
                  Cell(r.path_gap_m_max, 1.0, "%.3f").c_str());
    }
  }
  const std::vector<SweepCell> cells = SweepCells(rows);
  const std::vector<Paired> paired = PairLearnWithNominal(rows);
  if (seeds.size() > 1 && !rows.empty()) {
    // One seed's lap is one draw of the reality and one lap's chances: the
    // cells over the seeds, and learning against the nominal model seed by seed.
    std::printf(
        "\n  over %zu seeds: mean (sd) [95 %% interval of the mean]\n"
        "    vehicle  reality  predict  delay ms  loss %%  completed  lap s                     "
        "   err p95 mm\n",
        seeds.size());
    for (const SweepCell& c : cells) {
      const auto spread = [](const OverSeeds& o, double scale) {
        return Cell(o.mean, scale, "%.2f") + " (" + Cell(o.sd, scale, "%.2f") + ") [" +
               Cell(o.ci_low, scale, "%.2f") + ", " + Cell(o.ci_high, scale, "%.2f") + "]";
      };
      std::printf("    %-7s  %-7s  %-7s  %8.0f  %6.1f  %4zu/%-4zu  %-34s  %s\n",
                  c.vehicle->name.c_str(), std::filesystem::path(c.reality).stem().c_str(),
                  ModeName(c.mode), c.delay_ms, c.loss_percent, c.completed, c.laps,
                  spread(c.lap_time_s, 1.0).c_str(), spread(c.error_m_p95, 1e3).c_str());
    }
    if (!paired.empty()) {
      std::printf(
          "\n  learn - nominal, seed by seed (negative: learning better)\n"
          "    vehicle  reality  delay ms  loss %%  figure                  seeds  mean      "
          "95 %% interval          verdict\n");
      for (const Paired& p : paired) {
        const double scale = p.figure == "lap_time_s" ? 1.0 : 1e3;
        std::printf("    %-7s  %-7s  %8.0f  %6.1f  %-22s  %5zu  %8s  [%8s, %8s]  %s\n",
                    p.vehicle->name.c_str(), std::filesystem::path(p.reality).stem().c_str(),
                    p.delay_ms, p.loss_percent, p.figure == "lap_time_s" ? "lap s" : "error p95 mm",
                    p.difference.n, Cell(p.difference.mean, scale, "%+.2f").c_str(),
                    Cell(p.difference.ci_low, scale, "%+.2f").c_str(),
                    Cell(p.difference.ci_high, scale, "%+.2f").c_str(), p.Verdict());
      }
    }
  }
  const Targets targets = Judge(rows, paired);
  if (!rows.empty()) {
    std::printf(
        "\n  targets (the robot, 0 %% loss):\n"
        "    lab, 400 ms, learning: lap %s x the 0 ms lap (<= 1.3): %s; error p95 in the map's "
        "frame %s mm (<= 50): %s (in the world's %s mm)\n"
        "    harsh: every learning lap completed: %s; learning's error p95 below the nominal "
        "model's at every delay: %s\n"
        "    harsh over the seeds: learning better than nominal in every cell (lap and error p95 "
        "at each delay, the paired 95 %% interval below 0): %s\n"
        "    none (the twin): largest error p95 with prediction %s mm (must be ~0)\n",
        Cell(targets.lab_ratio_400ms, 1.0, "%.2f").c_str(), Verdict(targets.LabRatioMet()),
        Cell(targets.lab_error_m_p95_400ms, 1e3).c_str(), Verdict(targets.LabErrorMet()),
        Cell(targets.lab_error_world_m_p95_400ms, 1e3).c_str(), Verdict(targets.harsh_completed),
        Verdict(targets.harsh_learn_beats_nominal), Verdict(targets.harsh_learn_better_every_cell),
        Cell(targets.none_error_m_p95_max, 1e3, "%.2f").c_str());
  }
  {
    std::ofstream csv(dir / "link_laps.csv");
    csv << "vehicle,reality,seed,predict,delay_ms,loss_percent,outcome,completed,lap_time_s,"
           "ratio_to_0ms,gates_passed,gates_total,obstacles,rtt_p50_ms,prediction_error_m_p50,"
           "prediction_error_m_p95,prediction_error_odometry_m_p95,localisation_error_m_p95,"
           "odometry_error_m_p95,estimate_converged_s,"
           "path_gap_m_mean,path_gap_m_max,wall_s,judged_on,lap_time_live_s,gates_passed_live,"
           "prediction_error_world_m_p95,localisation_error_world_m_p95,map_learnt_m_rms,"
           "map_file_m_rms\n";
    std::ofstream est(dir / "link_estimates.csv");
    est << "vehicle,reality,seed,predict,delay_ms,loss_percent,param,estimate,truth,known_s\n";
    for (const LapRow& r : rows) {
      csv << r.spec.vehicle->name << "," << r.reality << "," << r.seed << ","
          << ModeName(r.spec.mode) << "," << r.spec.delay_ms << "," << r.spec.loss_percent << ","
          << r.outcome << "," << (r.completed ? 1 : 0) << "," << r.lap_time_s << ","
          << r.ratio_to_0ms << "," << r.gates_passed << "," << r.gates_total << "," << r.obstacles
          << "," << r.rtt_p50_ms << "," << r.error_m_p50 << "," << r.error_m_p95 << ","
          << r.odometry_error_m_p95 << "," << r.pose_error_m_p95 << ","
          << r.odometry_truth_error_m_p95 << "," << r.converged_s << "," << r.path_gap_m_mean << ","
          << r.path_gap_m_max << "," << r.wall_s << ","
          << (r.judged_on_truth ? "truth" : "odometry") << "," << r.lap_time_live_s << ","
          << r.gates_passed_live << "," << r.error_world_m_p95 << "," << r.pose_error_world_m_p95
          << "," << r.map_learnt_m_rms << "," << r.map_file_m_rms << "\n";
      for (const Estimate& e : r.estimated) {
        est << r.spec.vehicle->name << "," << r.reality << "," << r.seed << ","
            << ModeName(r.spec.mode) << "," << r.spec.delay_ms << "," << r.spec.loss_percent << ","
            << e.param << "," << e.estimate << "," << e.truth << "," << e.known_s << "\n";
      }
    }
  }
  // Per vehicle, one curve per reality and mode (at the first loss): the lap
  // against the delay, and the prediction's error against the truth; over
  // several seeds, each point the seeds' mean (completed laps only).
  for (const LapVehicle& vehicle : vehicles) {
    std::vector<Series> laps, errors;
    const std::string over = seeds.size() > 1 ? ", mean of seeds" : "";
    for (const std::string& reality : realities) {
      for (const PredictMode mode : modes) {
        Series lap{reality + ", " + ModeName(mode) + over, {}, {}};
        Series error = lap;
        for (const double delay : delays) {
          std::vector<double> lap_s, error_m;
          for (const LapRow& r : rows) {
            if (r.spec.vehicle != &vehicle || r.spec.reality != reality || r.spec.mode != mode ||
                r.spec.loss_percent != losses.front() || r.spec.delay_ms != delay)
              continue;
            if (r.completed) lap_s.push_back(r.lap_time_s);
            if (std::isfinite(r.error_m_p95)) error_m.push_back(r.error_m_p95);
          }
          if (!lap_s.empty()) {
            lap.x.push_back(delay);
            lap.y.push_back(Summarise(lap_s).mean);
          }
          if (!error_m.empty()) {
            error.x.push_back(delay);
            // log scale: a 10 µm floor
            error.y.push_back(std::max(Summarise(error_m).mean * 1e3, 0.01));
          }
        }
        if (!lap.x.empty()) laps.push_back(lap);
        if (!error.x.empty() && mode != PredictMode::kOff) errors.push_back(error);
      }
    }
    const std::string stem = vehicle.name == "robot" ? "link_laps" : "link_laps_" + vehicle.name;
    if (!laps.empty()) {
      PlotLines(
          dir / (stem + ".png"), laps,
          {"The lap against the link's delay, per reality and prediction (" + vehicle.name + ")",
           "delay each way, ms", "lap time, s (completed laps)"});
    }
    if (!errors.empty()) {
      PlotLines(dir / (stem + "_error.png"), errors,
                {"Prediction error p95 against the truth (" + vehicle.name + ")",
                 "delay each way, ms", "error p95, mm", true});
    }
  }
  const bool all_ran = std::all_of(rows.begin(), rows.end(), [](const LapRow& r) { return r.ran; });
  std::printf("\n  wrote %s/link_{rtt,laps,estimates}.csv, link_laps*.png, link_truth/\n",
              dir.c_str());
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
      o << (i ? "," : "") << "{\"vehicle\":" << JsonString(r.spec.vehicle->name)
        << ",\"reality\":{\"name\":" << JsonString(r.reality)
        << ",\"seed\":" << (r.seed.empty() ? std::string("null") : r.seed) << "}"
        << ",\"mode\":" << JsonString(ModeName(r.spec.mode))
        << ",\"predict\":" << (r.spec.mode != PredictMode::kOff ? "true" : "false")
        << ",\"delay_ms\":" << JsonNumber(r.spec.delay_ms)
        << ",\"loss_percent\":" << JsonNumber(r.spec.loss_percent)
        << ",\"outcome\":" << JsonString(r.outcome)
        << ",\"completed\":" << (r.completed ? "true" : "false")
        << ",\"lap_time_s\":" << JsonNumber(std::isfinite(r.lap_time_s) ? r.lap_time_s : -1.0)
        << ",\"judged_on\":" << JsonString(r.judged_on_truth ? "truth" : "odometry")
        << ",\"lap_time_live_s\":" << JsonOrNull(r.lap_time_live_s)
        << ",\"gates_passed\":" << r.gates_passed
        << ",\"gates_passed_live\":" << r.gates_passed_live
        << ",\"ratio_to_0ms\":" << JsonOrNull(r.ratio_to_0ms) << ",\"obstacles\":" << r.obstacles
        << ",\"rtt_p50_ms\":" << JsonNumber(std::isfinite(r.rtt_p50_ms) ? r.rtt_p50_ms : -1.0)
        << ",\"prediction_error_m_p50\":" << JsonOrNull(r.error_m_p50)
        << ",\"prediction_error_m_p95\":" << JsonOrNull(r.error_m_p95)
        << ",\"prediction_error_odometry_m_p95\":" << JsonOrNull(r.odometry_error_m_p95)
        << ",\"prediction_error_world_m_p95\":" << JsonOrNull(r.error_world_m_p95)
        << ",\"localisation_error_m_p95\":" << JsonOrNull(r.pose_error_m_p95)
        << ",\"localisation_error_world_m_p95\":" << JsonOrNull(r.pose_error_world_m_p95)
        << ",\"odometry_error_m_p95\":" << JsonOrNull(r.odometry_truth_error_m_p95)
        << ",\"map_learnt_m_rms\":" << JsonOrNull(r.map_learnt_m_rms)
        << ",\"map_file_m_rms\":" << JsonOrNull(r.map_file_m_rms)
        << ",\"estimate_converged_s\":" << JsonOrNull(r.converged_s) << ",\"estimated\":{";
      for (size_t k = 0; k < r.estimated.size(); ++k) {
        o << (k ? "," : "") << JsonString(r.estimated[k].param)
          << ":{\"estimate\":" << JsonOrNull(r.estimated[k].estimate)
          << ",\"truth\":" << JsonOrNull(r.estimated[k].truth)
          << ",\"known_s\":" << JsonOrNull(r.estimated[k].known_s) << "}";
      }
      o << "},\"path_gap_m_mean\":" << JsonOrNull(r.path_gap_m_mean)
        << ",\"path_gap_m_max\":" << JsonOrNull(r.path_gap_m_max)
        << ",\"wall_s\":" << JsonNumber(r.wall_s) << "}";
    }
    const auto spread_json = [](const OverSeeds& o) {
      return "{\"n\":" + std::to_string(o.n) + ",\"mean\":" + JsonOrNull(o.mean) +
             ",\"sd\":" + JsonOrNull(o.sd) + ",\"ci95\":[" + JsonOrNull(o.ci_low) + "," +
             JsonOrNull(o.ci_high) + "]}";
    };
    o << "],\"seeds\":[";
    for (size_t i = 0; i < seeds.size(); ++i)
      o << (i ? "," : "") << (seeds[i] ? std::to_string(*seeds[i]) : std::string("null"));
    o << "],\"simulated_time\":" << (simulated_time ? "true" : "false") << ",\"cells\":[";
    for (size_t i = 0; i < cells.size(); ++i) {
      const SweepCell& c = cells[i];
      o << (i ? "," : "") << "{\"vehicle\":" << JsonString(c.vehicle->name)
        << ",\"reality\":" << JsonString(std::filesystem::path(c.reality).stem().string())
        << ",\"mode\":" << JsonString(ModeName(c.mode))
        << ",\"delay_ms\":" << JsonNumber(c.delay_ms)
        << ",\"loss_percent\":" << JsonNumber(c.loss_percent) << ",\"laps\":" << c.laps
        << ",\"completed\":" << c.completed << ",\"lap_time_s\":" << spread_json(c.lap_time_s)
        << ",\"prediction_error_m_p50\":" << spread_json(c.error_m_p50)
        << ",\"prediction_error_m_p95\":" << spread_json(c.error_m_p95) << "}";
    }
    o << "],\"learn_minus_nominal\":[";
    for (size_t i = 0; i < paired.size(); ++i) {
      const Paired& p = paired[i];
      o << (i ? "," : "") << "{\"vehicle\":" << JsonString(p.vehicle->name)
        << ",\"reality\":" << JsonString(std::filesystem::path(p.reality).stem().string())
        << ",\"delay_ms\":" << JsonNumber(p.delay_ms)
        << ",\"loss_percent\":" << JsonNumber(p.loss_percent)
        << ",\"figure\":" << JsonString(p.figure) << ",\"difference\":" << spread_json(p.difference)
        << ",\"verdict\":" << JsonString(p.Verdict()) << "}";
    }
    o << "],\"targets\":{\"lab_ratio_400ms\":" << JsonOrNull(targets.lab_ratio_400ms)
      << ",\"lab_ratio_met\":" << JsonVerdict(targets.LabRatioMet())
      << ",\"lab_error_m_p95_400ms\":" << JsonOrNull(targets.lab_error_m_p95_400ms)
      << ",\"lab_error_met\":" << JsonVerdict(targets.LabErrorMet())
      << ",\"lab_error_world_m_p95_400ms\":" << JsonOrNull(targets.lab_error_world_m_p95_400ms)
      << ",\"harsh_completed\":" << JsonVerdict(targets.harsh_completed)
      << ",\"harsh_learn_beats_nominal\":" << JsonVerdict(targets.harsh_learn_beats_nominal)
      << ",\"harsh_learn_better_every_cell\":" << JsonVerdict(targets.harsh_learn_better_every_cell)
      << ",\"none_error_m_p95_max\":" << JsonOrNull(targets.none_error_m_p95_max) << "}}";
    std::printf("%s\n", JsonLine(o.str(), smoke).c_str());
  }
  return rtt_ok && all_ran ? 0 : 1;
}

}  // namespace haptel::bench
