#include "haptel/record/unsaved_run.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <stdexcept>

#include "haptel/core/json.hpp"

namespace haptel::record {
namespace {

/// A number that reads back to the same double (JsonNumber keeps 6 digits).
std::string Exact(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

class Object {
 public:
  Object& Raw(const char* key, const std::string& json) {
    out_ += out_.size() > 1 ? "," : "";
    out_ += JsonString(key) + ":" + json;
    return *this;
  }
  Object& Num(const char* key, double v) { return Raw(key, Exact(v)); }
  Object& Int(const char* key, int64_t v) { return Raw(key, std::to_string(v)); }
  Object& Bool(const char* key, bool v) { return Raw(key, v ? "true" : "false"); }
  Object& Str(const char* key, const std::string& v) { return Raw(key, JsonString(v)); }
  std::string Close() { return out_ + "}"; }

 private:
  std::string out_ = "{";
};

template <typename T, typename F>
std::string Array(const std::vector<T>& items, F&& one) {
  std::string out = "[";
  for (const T& item : items) {
    if (out.size() > 1) out += ",";
    out += one(item);
  }
  return out + "]";
}

/// Writes `text` to `file` — or, when that exists, to `file` with "-2", "-3",
/// ... before its extension — never over an existing file. Returns the error
/// ("" when written) and sets `file` to the one written.
std::string WriteNew(std::filesystem::path& file, const std::string& text) {
  std::FILE* f = nullptr;
  const std::filesystem::path first = file;
  for (int n = 2; (f = std::fopen(file.c_str(), "wx")) == nullptr && errno == EEXIST && n < 100;
       ++n) {
    file = first;
    file.replace_extension("");
    file += "-" + std::to_string(n) + first.extension().string();
  }
  if (f == nullptr) return std::strerror(errno);
  std::string error;
  if (std::fwrite(text.data(), 1, text.size(), f) != text.size()) error = std::strerror(errno);
  if (std::fclose(f) != 0 && error.empty()) error = std::strerror(errno);
  if (!error.empty()) std::remove(file.c_str());
  return error;
}

}  // namespace

std::string RunRecordJson(const RunRecord& r) {
  std::string counters = "{";
  for (const RunCounter& c : r.counters) {
    if (counters.size() > 1) counters += ",";
    counters += JsonString(c.name) + ":" + std::to_string(c.value);
  }
  counters += "}";
  // The truth's lap as the database stores it (v16): null when not judged.
  const TruthLap& t = r.truth_lap;
  const auto judged = [&](const std::string& value) { return t.judged ? value : "null"; };
  return Object()
      .Int("started_wall_ns", r.started_wall_ns)
      .Str("config_name", r.config_name)
      .Str("track", r.track)
      .Str("interface", r.interface)
      .Str("vehicle", r.vehicle)
      .Bool("completed", r.completed)
      .Str("outcome", r.outcome)
      .Num("lap_time_s", r.lap_time_s)
      .Num("approach_s", r.approach_s)
      .Int("gates_passed", r.gates_passed)
      .Int("gates_total", r.gates_total)
      .Int("gates_missed", r.gates_missed)
      .Int("obstacles_touched", r.obstacles_touched)
      .Int("vehicle_pid", r.vehicle_pid)
      .Num("servo_rate_hz", r.servo_rate_hz)
      .Num("servo_period_p99_us", r.servo_period_p99_us)
      .Num("command_rtt_ms_p50", r.command_rtt_ms_p50)
      .Num("command_rtt_ms_p99", r.command_rtt_ms_p99)
      .Int("video_frames", r.video_frames)
      .Num("video_fps", r.video_fps)
      .Num("video_latency_ms_p50", r.video_latency_ms_p50)
      .Num("video_kbps", r.video_kbps)
      .Num("video_stale_s", r.video_stale_s)
      .Bool("predict", r.predict)
      .Str("link_fault", r.link_fault)
      .Num("prediction_error_m_p50", r.prediction_error_m_p50)
      .Num("prediction_error_m_p95", r.prediction_error_m_p95)
      .Num("speedup", r.speedup)
      .Int("controller_errors", r.controller_errors)
      .Str("operator", r.operator_kind)
      .Str("device", r.device)
      .Num("disengaged_s", r.disengaged_s)
      .Num("pseudo_haptic_gain_mean", r.pseudo_haptic_gain_mean)
      .Int("ff_effects_played", r.ff_effects_played)
      .Raw("completed_truth", judged(t.completed ? "true" : "false"))
      .Num("lap_time_truth_s", t.lap_time_s)
      .Raw("lap_time_truth_projected", judged(t.projected ? "true" : "false"))
      .Raw("gates_truth_passed", judged(std::to_string(t.gates_passed)))
      .Raw("gates_truth_missed", judged(std::to_string(t.gates_missed)))
      .Num("distance_m", r.distance_m)
      .Num("view_fps", r.view_fps)
      .Num("view_frame_p99_ms", r.view_frame_p99_ms)
      .Num("video_to_screen_ms_p50", r.video_to_screen_ms_p50)
      .Num("video_to_screen_ms_p99", r.video_to_screen_ms_p99)
      .Str("picture", r.picture)
      .Num("servo_target_hz", r.servo_target_hz)
      .Bool("servo_rate_short", r.servo_rate_short)
      .Num("physics_rate_hz", r.physics_rate_hz)
      .Num("physics_target_hz", r.physics_target_hz)
      .Bool("physics_rate_short", r.physics_rate_short)
      .Raw("counters", counters)
      .Raw("splits", Array(r.splits,
                           [](const GateSplit& s) {
                             return Object()
                                 .Int("gate", s.gate)
                                 .Bool("passed", s.passed)
                                 .Num("split_s", s.split_s)
                                 .Close();
                           }))
      .Raw("switches",
           Array(r.switches,
                 [](const SwitchRecord& s) {
                   return Object().Num("t_s", s.t_s).Str("from", s.from).Str("to", s.to).Close();
                 }))
      .Raw("path", Array(r.path,
                         [](const PathPoint& p) {
                           return Object()
                               .Num("t_s", p.t_s)
                               .Num("x", p.x)
                               .Num("y", p.y)
                               .Num("speed_mps", p.speed_mps)
                               .Close();
                         }))
      .Raw("contacts",
           Array(r.contacts,
                 [](const ContactPoint& c) {
                   return Object().Num("t_s", c.t_s).Num("x", c.x).Num("y", c.y).Close();
                 }))
      .Close();
}

std::filesystem::path UnsavedRunPath(const std::filesystem::path& database, int64_t wall_ns) {
  constexpr int64_t kNsPerS = 1'000'000'000;
  const auto seconds = static_cast<std::time_t>(wall_ns / kNsPerS);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char stamp[40];
  std::snprintf(stamp, sizeof stamp, "%04d%02d%02dT%02d%02d%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>((wall_ns % kNsPerS) / 1'000'000));
  return std::filesystem::path(database.string() + ".unsaved-" + stamp + ".json");
}

std::filesystem::path WriteUnsavedRun(const RunRecord& run, const std::filesystem::path& database,
                                      int64_t wall_ns, const std::optional<TrialOfRun>& trial) {
  std::string text = RunRecordJson(run);
  if (trial) {
    const std::string owner = Object()
                                  .Str("study", trial->study)
                                  .Str("participant", trial->participant)
                                  .Int("position", trial->position)
                                  .Str("condition", trial->condition)
                                  .Int("repetition", trial->repetition)
                                  .Close();
    text = "{\"trial\":" + owner + "," + text.substr(1);
  }
  text += "\n";
  std::filesystem::path beside = UnsavedRunPath(database, wall_ns);
  const std::string beside_error = WriteNew(beside, text);
  if (beside_error.empty()) return beside;
  std::error_code ec;
  std::filesystem::path temp = std::filesystem::temp_directory_path(ec) / beside.filename();
  const std::string temp_error = ec ? ec.message() : WriteNew(temp, text);
  if (temp_error.empty()) return temp;
  throw std::runtime_error("cannot write the results to " + beside.string() + " (" + beside_error +
                           ") nor to " + temp.string() + " (" + temp_error + ")");
}

}  // namespace haptel::record
