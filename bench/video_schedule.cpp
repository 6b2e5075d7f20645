#include "video_schedule.hpp"

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <fstream>
#include <memory>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "haptel/config/link.hpp"
#include "haptel/core/child_process.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "haptel/video/image_quality.hpp"
#include "plot.hpp"
#include "video_source.hpp"

namespace haptel::bench {
namespace {

constexpr double kCommandRateHz = 100.0;
constexpr double kLatencyLimit_ms = 150.0;  ///< issue 24's target for the video latency p95
constexpr double kWindow_s = 1.0;           ///< adapt_s's trailing window
constexpr double kSsimPerSecond = 3.0;      ///< pictures compared with their source

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  const size_t k =
      std::min(v.size() - 1, static_cast<size_t>(std::floor(q * static_cast<double>(v.size()))));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

/// One picture as the view got it.
struct Shown {
  double t_s;  ///< since the schedule began
  double latency_ms;
  int phase;
};

/// The latency p95 over the trailing window ending at `t_s` (NaN: no picture in it).
double WindowP95(const std::vector<Shown>& shown, double t_s) {
  std::vector<double> in;
  for (const Shown& s : shown) {
    if (s.t_s > t_s - kWindow_s && s.t_s <= t_s) in.push_back(s.latency_ms);
  }
  return Percentile(in, 0.95);
}

/// After a step down at `step_s`: when the window p95 is back under the
/// limit, counted from the step (0: never over in the first window after
/// it; `phase_s` when it never came back).
double AdaptSeconds(const std::vector<Shown>& shown, double step_s, double phase_s) {
  bool was_over = false;
  for (double t = step_s; t <= step_s + phase_s; t += 0.05) {
    const double p95 = WindowP95(shown, t);
    if (std::isnan(p95)) {  // no picture for a whole window: as bad as late
      was_over = true;
      continue;
    }
    if (p95 >= kLatencyLimit_ms) {
      was_over = true;
    } else if (was_over || t - step_s >= kWindow_s) {
      return was_over ? t - step_s : 0.0;
    }
  }
  return phase_s;
}

}  // namespace

mediator::VehicleLinkOptions ScheduleLinkOptions(VehicleConfig vehicle, int domain,
                                                 double first_kbps,
                                                 std::filesystem::path track_file) {
  mediator::VehicleLinkOptions link_options;
  link_options.vehicle = std::move(vehicle);
  link_options.link = link_options.vehicle.link;
  link_options.link.domain_id = domain;
  char fault[48];
  std::snprintf(fault, sizeof fault, "rate=%gkbit", first_kbps);
  link_options.link.fault = ParseLinkFault(fault);
  link_options.track_file = std::move(track_file);
  link_options.program = ProgramDirectory() / "haptel-vehicle";
  link_options.decode_video = true;
  return link_options;
}

ScheduleResult RunCapacitySchedule(const VehicleConfig& vehicle, CameraCodec codec,
                                   const std::vector<cv::Mat>& frames,
                                   const ScheduleOptions& options) {
  ScheduleResult result;
  result.codec = codec;
  const std::string name = std::string("video_schedule_") + CameraCodecName(codec);
  const std::filesystem::path source = options.out_dir / "video_schedule_source.mkv";
  const std::filesystem::path vehicle_file = options.out_dir / (name + "_vehicle.yaml");
  const double rate_hz = vehicle.camera.rate_hz;
  const size_t n_phases = options.capacities_kbps.size();
  std::vector<Shown> shown;
  struct TracePoint {
    double t_s, capacity_kbps, video_kbps, target_kbps, latency_p95_ms;
  };
  std::vector<TracePoint> trace;
  try {
    if (!std::filesystem::exists(source)) WriteLosslessSource(source, frames, rate_hz);
    WriteVehicleFileWithSource(vehicle, codec, source, vehicle_file);
    mediator::VehicleLink link(ScheduleLinkOptions(LoadVehicle(vehicle_file), options.domain,
                                                   options.capacities_kbps.front(),
                                                   options.track_file));
    link::FaultLine* line = link.fault_line();
    if (line == nullptr) throw std::logic_error("the operator's side has no fault line");
    // Up: a state and a first picture.
    const int64_t up_until = MonotonicNs() + SToNs(30.0);
    while (MonotonicNs() < up_until &&
           (link.last_received_ns() == 0 || link.video().Latest().id == 0)) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (!link.ProcessAlive())
        throw std::runtime_error("haptel-vehicle ended: " + link.ExitDescription());
    }
    if (link.video().Latest().id == 0)
      throw std::runtime_error("no video from the vehicle within 30 s");

    SsimWorker ssim(frames, rate_hz, n_phases);
    const int64_t start_ns = MonotonicNs();
    uint64_t last_id = link.video().Latest().id;
    int64_t next_command = start_ns, next_ssim = start_ns, next_trace = start_ns;
    int tick = 0;
    // The bytes received, sampled, for a trailing 1 s bitrate.
    std::deque<std::pair<int64_t, uint64_t>> byte_samples;
    for (size_t p = 0; p < n_phases; ++p) {
      SchedulePhase phase;
      phase.capacity_kbps = options.capacities_kbps[p];
      phase.step_down = p > 0 && phase.capacity_kbps < options.capacities_kbps[p - 1];
      line->SetRate(phase.capacity_kbps * 1000.0);
      link.ResetRtt();
      const video::VideoStats before = link.video().Stats();
      const int64_t phase_start = MonotonicNs();
      const int64_t phase_end = start_ns + SToNs(options.phase_s * static_cast<double>(p + 1));
      std::vector<double> latencies;
      uint64_t pictures = 0;
      while (MonotonicNs() < phase_end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        const int64_t now = MonotonicNs();
        if (now >= next_command) {
          next_command += static_cast<int64_t>(1e9 / kCommandRateHz);
          if (next_command < now) next_command = now;      // behind: no burst to catch up
          const double v = 0.2 * std::sin(++tick * 0.02);  // a gentle back-and-forth near the start
          link.Send(TreadCommand{v, v});
          link.channel<link::RobotMessages>().inbox().Drain();
        }
        const video::Frame latest = link.video().Latest();
        if (latest.id != last_id && !latest.stale && latest.decoded_wall_ns != 0) {
          last_id = latest.id;
          ++pictures;
          const double latency_ms =
              static_cast<double>(latest.decoded_wall_ns - latest.capture_wall_ns) * 1e-6;
          latencies.push_back(latency_ms);
          shown.push_back({NsToS(now - start_ns), latency_ms, static_cast<int>(p)});
          if (now >= next_ssim &&
              ssim.Offer(latest.image, latest.capture_wall_ns, static_cast<int>(p))) {
            next_ssim = now + static_cast<int64_t>(1e9 / kSsimPerSecond);
          }
        }
        if (now >= next_trace) {
          next_trace += SToNs(0.1);
          const video::VideoStats s = link.video().Stats();
          byte_samples.emplace_back(now, s.bytes);
          while (byte_samples.size() > 1 && byte_samples.front().first < now - SToNs(kWindow_s)) {
            byte_samples.pop_front();
          }
          const double span = NsToS(now - byte_samples.front().first);
          const double kbps =
              span > 0
                  ? static_cast<double>(s.bytes - byte_samples.front().second) * 8.0 / span / 1000.0
                  : 0.0;
          trace.push_back({NsToS(now - start_ns), phase.capacity_kbps, kbps, s.target_kbps,
                           WindowP95(shown, NsToS(now - start_ns))});
        }
      }
      const video::VideoStats after = link.video().Stats();
      const double seconds = NsToS(MonotonicNs() - phase_start);
      phase.video_kbps = static_cast<double>(after.bytes - before.bytes) * 8.0 / seconds / 1000.0;
      phase.target_kbps = after.target_kbps;
      phase.fps = static_cast<double>(pictures) / seconds;
      phase.latency_ms_p50 = Percentile(latencies, 0.5);
      phase.latency_ms_p95 = Percentile(latencies, 0.95);
      phase.frames_lost = after.frames_lost - before.frames_lost;
      phase.stale_s = after.stale_s - before.stale_s;
      phase.command_rtt_ms_p99 = link.Rtt().Percentile(0.99) * 1e-3;
      result.phases.push_back(phase);
      if (!link.ProcessAlive())
        throw std::runtime_error("haptel-vehicle ended: " + link.ExitDescription());
    }
    for (size_t p = 0; p < n_phases; ++p) {
      const auto [mean, count] = ssim.Phase(static_cast<int>(p));
      result.phases[p].ssim = mean;
      result.phases[p].ssim_samples = count;
      if (result.phases[p].step_down) {
        result.phases[p].adapt_s =
            AdaptSeconds(shown, options.phase_s * static_cast<double>(p), options.phase_s);
        result.adapt_s = std::max(result.adapt_s, result.phases[p].adapt_s);
      }
    }
    link.Stop();
    result.ok = std::all_of(result.phases.begin(), result.phases.end(),
                            [](const SchedulePhase& p) { return p.fps > 0; });
    if (!result.ok) result.error = "a phase without video";
  } catch (const std::exception& e) {
    result.error = e.what();
    return result;
  }

  std::ofstream csv(options.out_dir / (name + ".csv"));
  csv << "codec,capacity_kbps,video_kbps,target_kbps,ssim,ssim_samples,fps,latency_ms_p50,latency_"
         "ms_p95,"
         "frames_lost,stale_s,command_rtt_ms_p99,adapt_s\n";
  for (const SchedulePhase& p : result.phases) {
    csv << CameraCodecName(codec) << ',' << p.capacity_kbps << ',' << p.video_kbps << ','
        << p.target_kbps << ',' << p.ssim << ',' << p.ssim_samples << ',' << p.fps << ','
        << p.latency_ms_p50 << ',' << p.latency_ms_p95 << ',' << p.frames_lost << ',' << p.stale_s
        << ',' << p.command_rtt_ms_p99 << ',' << p.adapt_s << '\n';
  }
  std::ofstream trace_csv(options.out_dir / (name + "_trace.csv"));
  trace_csv << "t_s,capacity_kbps,video_kbps,target_kbps,latency_ms_p95_1s\n";
  Series capacity{"link capacity", {}, {}}, bitrate{"video received (1 s)", {}, {}},
      target{"estimator's target", {}, {}}, latency{"video latency p95 (1 s window)", {}, {}},
      limit{"150 ms", {}, {}};
  for (const TracePoint& t : trace) {
    trace_csv << t.t_s << ',' << t.capacity_kbps << ',' << t.video_kbps << ',' << t.target_kbps
              << ',' << t.latency_p95_ms << '\n';
    capacity.x.push_back(t.t_s), capacity.y.push_back(t.capacity_kbps);
    bitrate.x.push_back(t.t_s), bitrate.y.push_back(t.video_kbps);
    target.x.push_back(t.t_s), target.y.push_back(std::min(t.target_kbps, 3000.0));
    if (std::isfinite(t.latency_p95_ms))
      latency.x.push_back(t.t_s), latency.y.push_back(t.latency_p95_ms);
    limit.x.push_back(t.t_s), limit.y.push_back(kLatencyLimit_ms);
  }
  // Two plots, one above the other, in one picture.
  const std::filesystem::path top = options.out_dir / (name + "_rate.png");
  const std::filesystem::path bottom = options.out_dir / (name + "_latency.png");
  const std::string codec_name = CameraCodecName(codec);
  PlotLines(top, {capacity, target, bitrate},
            {"capacity schedule (" + codec_name + "): link rate and video bitrate", "time, s",
             "kbit/s (target shown up to 3000)", false, 900, 360});
  PlotLines(bottom, {latency, limit},
            {"capture to decoded latency", "time, s", "ms", false, 900, 300});
  // Each as wide as its legend makes it: the narrower padded white on the right.
  cv::Mat upper = cv::imread(top.string()), lower = cv::imread(bottom.string());
  const int width = std::max(upper.cols, lower.cols);
  for (cv::Mat* m : {&upper, &lower}) {
    if (m->cols < width)
      cv::copyMakeBorder(*m, *m, 0, 0, 0, width - m->cols, cv::BORDER_CONSTANT,
                         cv::Scalar(255, 255, 255));
  }
  cv::Mat stacked;
  cv::vconcat(upper, lower, stacked);
  cv::imwrite((options.out_dir / (name + ".png")).string(), stacked);
  std::filesystem::remove(top);
  std::filesystem::remove(bottom);
  return result;
}

}  // namespace haptel::bench
