#include "video_cameras.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>

#include "haptel/core/clock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "haptel/video/video_receiver.hpp"
#include "video_schedule.hpp"

namespace haptel::bench {
namespace {

constexpr char kSurveillance[] = "surveillance";
constexpr double kAimEvery_s = 0.5;
constexpr double kCommandRateHz = 10.0;

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

/// One camera's pictures as the receiver hands them, counted per phase.
struct Watch {
  uint64_t last_id = 0;
  uint64_t pictures = 0;
  std::vector<double> latencies_ms;
  /// A new decoded picture: counted, its latency kept. True when there was one.
  bool Poll(const video::Frame& f) {
    if (f.id == last_id || f.stale || f.decoded_wall_ns == 0) return false;
    last_id = f.id;
    ++pictures;
    latencies_ms.push_back(static_cast<double>(f.decoded_wall_ns - f.capture_wall_ns) * 1e-6);
    return true;
  }
  CameraPhaseFigures Figures(uint64_t bytes, double seconds) const {
    return {static_cast<double>(pictures) / seconds,
            static_cast<double>(bytes) * 8.0 / seconds / 1000.0, Percentile(latencies_ms, 0.5),
            Percentile(latencies_ms, 0.95)};
  }
};

}  // namespace

TwoCameraResult RunTwoCameraSchedule(const TwoCameraOptions& options) {
  TwoCameraResult result;
  try {
    const VehicleConfig vehicle = LoadVehicle(options.vehicle_file);
    if (vehicle.extra_cameras.empty() || vehicle.extra_cameras[0].name != kSurveillance) {
      throw std::runtime_error(options.vehicle_file.string() +
                               ": expected a second camera named surveillance");
    }
    mediator::VehicleLink link(ScheduleLinkOptions(vehicle, options.domain,
                                                   options.capacities_kbps.front(), vehicle.world));
    link::FaultLine* line = link.fault_line();
    if (line == nullptr) throw std::logic_error("the receiving side has no fault line");
    video::VideoReceiver surveillance(link.participant(), vehicle.name, link.session(), true,
                                      kSurveillance);
    link::CameraCommandWriter aim_writer(link.participant(),
                                         link::CameraCommandTopic(vehicle.name, kSurveillance),
                                         link::CameraMessages::kCommandProfile);
    msg::CameraCommand command;
    command.session(link.session());
    command.operator_name("haptel bench video");
    uint64_t seq = 0;
    CameraAim aim{0.0, -0.2, 2.0};
    const CameraRange range = vehicle.extra_cameras[0].Range();
    const auto send = [&] {
      link::CameraMessages::Encode(kSurveillance, Clamped(aim, range), command);
      command.seq(++seq);
      command.sent_ns(MonotonicNs());
      aim_writer.Write(command);
    };
    // Up: a picture from each camera.
    const int64_t up_until = MonotonicNs() + SToNs(30.0);
    while (MonotonicNs() < up_until &&
           (link.video().Latest().id == 0 || surveillance.Latest().id == 0)) {
      send();
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (!link.ProcessAlive())
        throw std::runtime_error("haptel-vehicle ended: " + link.ExitDescription());
    }
    if (link.video().Latest().id == 0 || surveillance.Latest().id == 0)
      throw std::runtime_error("no picture from both cameras within 30 s");

    // Aim changes: their seq → when sent (wall clock, as the decoded stamps).
    std::map<uint64_t, int64_t> aims_sent;
    std::vector<double> aim_latencies;
    uint64_t shown_up_to = seq;  // commands before the schedule are not timed
    const int64_t start_ns = MonotonicNs();
    int64_t next_command = start_ns, next_aim = start_ns;
    int turn = 0;
    Watch pilot_watch, surv_watch;
    for (size_t p = 0; p < options.capacities_kbps.size(); ++p) {
      TwoCameraPhase phase;
      phase.capacity_kbps = options.capacities_kbps[p];
      line->SetRate(phase.capacity_kbps * 1000.0);
      const uint64_t pilot_bytes = link.video().Stats().bytes;
      const uint64_t surv_bytes = surveillance.Stats().bytes;
      pilot_watch = {link.video().Latest().id, 0, {}};
      surv_watch = {surveillance.Latest().id, 0, {}};
      const int64_t phase_start = MonotonicNs();
      const int64_t phase_end = start_ns + SToNs(options.phase_s * static_cast<double>(p + 1));
      while (MonotonicNs() < phase_end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        const int64_t now = MonotonicNs();
        if (now >= next_aim) {
          next_aim += SToNs(kAimEvery_s);
          ++turn;
          aim = {0.4 * ((turn % 4) - 1.5), -0.2, turn % 2 == 0 ? 2.0 : 6.0};
          send();
          aims_sent[seq] = WallNs();
          ++result.aims;
          next_command = now + static_cast<int64_t>(1e9 / kCommandRateHz);
        } else if (now >= next_command) {
          next_command += static_cast<int64_t>(1e9 / kCommandRateHz);
          send();  // the same aim again: the holder's lease
        }
        pilot_watch.Poll(link.video().Latest());
        const video::Frame surv = surveillance.Latest();
        if (surv_watch.Poll(surv) && surv.command_seq > shown_up_to) {
          // The first picture since these commands: each aim change up to it is shown now.
          for (auto it = aims_sent.upper_bound(shown_up_to);
               it != aims_sent.end() && it->first <= surv.command_seq; ++it) {
            aim_latencies.push_back(static_cast<double>(surv.decoded_wall_ns - it->second) * 1e-6);
            ++result.aims_shown;
          }
          shown_up_to = surv.command_seq;
        }
      }
      const double seconds = NsToS(MonotonicNs() - phase_start);
      phase.pilot = pilot_watch.Figures(link.video().Stats().bytes - pilot_bytes, seconds);
      phase.surveillance = surv_watch.Figures(surveillance.Stats().bytes - surv_bytes, seconds);
      result.phases.push_back(phase);
      if (!link.ProcessAlive())
        throw std::runtime_error("haptel-vehicle ended: " + link.ExitDescription());
    }
    link.Stop();
    result.aim_latency_ms_p50 = Percentile(aim_latencies, 0.5);
    result.aim_latency_ms_p95 = Percentile(aim_latencies, 0.95);
    result.ok = std::all_of(result.phases.begin(), result.phases.end(), [](const auto& p) {
      return p.pilot.fps > 0 && p.surveillance.fps > 0;
    });
    if (!result.ok) result.error = "a phase without pictures from both cameras";
  } catch (const std::exception& e) {
    result.error = e.what();
    return result;
  }
  std::ofstream csv(options.out_dir / "video_cameras.csv");
  csv << "capacity_kbps,camera,fps,kbps,latency_ms_p50,latency_ms_p95\n";
  for (const TwoCameraPhase& p : result.phases) {
    for (const auto& [name, f] :
         {std::pair{"pilot", p.pilot}, std::pair{"surveillance", p.surveillance}}) {
      csv << p.capacity_kbps << ',' << name << ',' << f.fps << ',' << f.kbps << ','
          << f.latency_ms_p50 << ',' << f.latency_ms_p95 << '\n';
    }
  }
  return result;
}

}  // namespace haptel::bench
