#include "video_cameras.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>

#include "haptel/core/clock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/mediator/vehicle_link.hpp"
#include "haptel/video/video_receiver.hpp"
#include "haptel/view/head_source.hpp"
#include "plot.hpp"
#include "video_schedule.hpp"

namespace haptel::bench {
namespace {

constexpr char kSurveillance[] = "surveillance";
constexpr double kAimEvery_s = 0.5;
constexpr double kCommandRateHz = 10.0;
constexpr double kPilotCommandRateHz = 50.0;  ///< the blimp session's command rate

/// The pilot's head, moved by a mouse and a stick in turn, sent as the
/// blimp's camera pan; each motion timed to the first picture that shows it.
class HeadMotions {
 public:
  explicit HeadMotions(mediator::VehicleLink& link) : link_(link), stick_(HeadConfig{}, {}) {
    person_.pad_connected = true;
  }
  /// Every 0.5 s a motion, the mouse's (a drag: the pan jumps 0.5 rad) and
  /// the stick's (full deflection for 0.2 s) in turn; the command at 50 Hz.
  void Tick(int64_t now_ns) {
    if (start_ns_ == 0) start_ns_ = now_ns;
    const double t = NsToS(now_ns - start_ns_);
    if (now_ns >= next_motion_ns_) {
      next_motion_ns_ = now_ns + SToNs(0.5);
      by_stick_ = !by_stick_;
      motion_wall_ns_ = WallNs();
      motion_pending_ = true;
      if (by_stick_) {
        right_x_ = right_x_ > 0 ? -1.0 : 1.0;
        stick_until_ns_ = now_ns + SToNs(0.2);
      } else {
        person_.head_pan = person_.head_pan > 0 ? -0.5 : 0.5;
      }
    }
    person_.pad_axes[static_cast<size_t>(interfaces::PadAxis::kRightX)] =
        by_stick_ && now_ns < stick_until_ns_ ? right_x_ : 0.0;
    if (now_ns < next_command_ns_) return;
    next_command_ns_ = now_ns + static_cast<int64_t>(1e9 / kPilotCommandRateHz);
    // Both heads follow the person each tick; the one moved last turns the camera.
    const double mouse_pan = mouse_.Update(t, person_).pan;
    const double stick_pan = stick_.Update(t, person_).pan;
    const double pan = by_stick_ ? stick_pan : mouse_pan;
    const double before = by_stick_ ? stick_pan_ : mouse_pan_;
    mouse_pan_ = mouse_pan;
    stick_pan_ = stick_pan;
    BlimpCommand command;
    command.camera_pan = pan;
    link_.Send(command);
    if (motion_pending_ && pan != before) {
      // The first command carrying this motion: its seq, and when the head moved.
      motion_pending_ = false;
      const uint64_t seq = link_.channel<link::BlimpMessages>().Counts().commands_sent;
      moves_[seq] = {motion_wall_ns_, by_stick_};
      ++(by_stick_ ? gamepad_.moves : mouse_figures_.moves);
    }
  }
  /// A pilot picture: the motions it is the first to show.
  void OnPicture(const video::Frame& f) {
    for (auto it = moves_.begin(); it != moves_.end() && it->first <= f.command_seq;) {
      const double ms = static_cast<double>(f.decoded_wall_ns - it->second.wall_ns) * 1e-6;
      (it->second.stick ? gamepad_ms_ : mouse_ms_).push_back(ms);
      ++(it->second.stick ? gamepad_.shown : mouse_figures_.shown);
      it = moves_.erase(it);
    }
  }
  HeadLatency Mouse() const { return Figures(mouse_figures_, mouse_ms_); }
  HeadLatency Gamepad() const { return Figures(gamepad_, gamepad_ms_); }

 private:
  struct Move {
    int64_t wall_ns;
    bool stick;
  };
  static HeadLatency Figures(HeadLatency h, const std::vector<double>& ms);
  mediator::VehicleLink& link_;
  view::MouseHead mouse_;
  view::GamepadHead stick_;
  interfaces::InputState person_;
  int64_t start_ns_ = 0, next_motion_ns_ = 0, next_command_ns_ = 0, stick_until_ns_ = 0;
  int64_t motion_wall_ns_ = 0;
  bool by_stick_ = true, motion_pending_ = false;
  double right_x_ = -1.0, mouse_pan_ = 0.0, stick_pan_ = 0.0;
  std::map<uint64_t, Move> moves_;
  HeadLatency mouse_figures_, gamepad_;
  std::vector<double> mouse_ms_, gamepad_ms_;
};

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
    CameraPhaseFigures f;
    f.fps = static_cast<double>(pictures) / seconds;
    f.kbps = static_cast<double>(bytes) * 8.0 / seconds / 1000.0;
    f.latency_ms_p50 = Percentile(latencies_ms, 0.5);
    f.latency_ms_p95 = Percentile(latencies_ms, 0.95);
    return f;
  }
};

HeadLatency HeadMotions::Figures(HeadLatency h, const std::vector<double>& ms) {
  h.ms_p50 = Percentile(ms, 0.5);
  h.ms_p95 = Percentile(ms, 0.95);
  return h;
}

}  // namespace

TwoCameraResult RunTwoCameraSchedule(const TwoCameraOptions& options) {
  TwoCameraResult result;
  try {
    const VehicleConfig vehicle = LoadVehicle(options.vehicle_file);
    if (vehicle.extra_cameras.empty() || vehicle.extra_cameras[0].name != kSurveillance) {
      throw std::runtime_error(options.vehicle_file.string() +
                               ": expected a second camera named surveillance");
    }
    const mediator::VehicleLinkOptions link_options = ScheduleLinkOptions(
        vehicle, options.domain, options.capacities_kbps.front(), vehicle.world);
    mediator::VehicleLink link(link_options);
    link::FaultLine* line = link.fault_line();
    if (line == nullptr) throw std::logic_error("the receiving side has no fault line");
    video::VideoReceiver surveillance(link.participant(), vehicle.name, link.session(), true,
                                      kSurveillance);
    // The vehicle's share for each camera (LinkShare's target), as its status says.
    std::atomic<uint32_t> pilot_share{0}, surv_share{0};
    link::CameraStatusReader status(
        link.participant(), link::CameraStatusTopic(vehicle.name),
        link::CameraMessages::kStatusProfile, [&](const msg::CameraStatus& st) {
          for (const msg::CameraInfo& c : st.cameras()) {
            (c.driven() ? pilot_share : surv_share).store(c.target_kbps());
          }
        });
    // The surveillance camera's holder is a station of its own: a participant
    // that holds a camera may not drive, and the pilot's head commands do.
    link::Participant station(link_options.link, "haptel-bench-station");
    link::CameraCommandWriter aim_writer(station,
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
    std::ofstream trace(options.out_dir / "video_cameras_trace.csv");
    trace << "t_s,capacity_kbps,pilot_kbps,surveillance_kbps,pilot_share_kbps,"
             "surveillance_share_kbps\n";
    Series capacity_series{"capacity", {}, {}}, pilot_series{"pilot", {}, {}},
        surv_series{"surveillance", {}, {}}, pilot_share_series{"pilot share", {}, {}},
        surv_share_series{"surveillance share", {}, {}};
    constexpr double kTraceEvery_s = 0.5;
    int64_t next_trace = start_ns + SToNs(kTraceEvery_s);
    uint64_t traced_pilot = link.video().Stats().bytes, traced_surv = surveillance.Stats().bytes;
    HeadMotions head(link);
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
      const int64_t half = phase_start + (phase_end - phase_start) / 2;
      uint64_t pilot_half_bytes = 0, surv_half_bytes = 0;
      int64_t half_start = 0;
      double pilot_share_sum = 0, surv_share_sum = 0;
      int share_samples = 0;
      const size_t aims_before = aim_latencies.size();
      while (MonotonicNs() < phase_end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        const int64_t now = MonotonicNs();
        if (now >= half && half_start == 0) {
          half_start = now;
          pilot_half_bytes = link.video().Stats().bytes;
          surv_half_bytes = surveillance.Stats().bytes;
        }
        if (now >= next_trace) {
          next_trace += SToNs(kTraceEvery_s);
          const uint64_t pb = link.video().Stats().bytes, sb = surveillance.Stats().bytes;
          const double t = NsToS(now - start_ns);
          const double to_kbps = 8.0 / 1000.0 / kTraceEvery_s;
          const double pk = static_cast<double>(pb - traced_pilot) * to_kbps;
          const double sk = static_cast<double>(sb - traced_surv) * to_kbps;
          traced_pilot = pb;
          traced_surv = sb;
          trace << t << ',' << phase.capacity_kbps << ',' << pk << ',' << sk << ','
                << pilot_share.load() << ',' << surv_share.load() << '\n';
          for (auto [series, y] : {std::pair{&capacity_series, phase.capacity_kbps},
                                   std::pair{&pilot_series, pk}, std::pair{&surv_series, sk},
                                   std::pair{&pilot_share_series, 1.0 * pilot_share.load()},
                                   std::pair{&surv_share_series, 1.0 * surv_share.load()}}) {
            series->x.push_back(t);
            series->y.push_back(y);
          }
          if (half_start != 0) {
            pilot_share_sum += pilot_share.load();
            surv_share_sum += surv_share.load();
            ++share_samples;
          }
        }
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
        head.Tick(now);
        if (const video::Frame pilot = link.video().Latest(); pilot_watch.Poll(pilot))
          head.OnPicture(pilot);
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
      const int64_t phase_stop = MonotonicNs();
      const double seconds = NsToS(phase_stop - phase_start);
      phase.pilot = pilot_watch.Figures(link.video().Stats().bytes - pilot_bytes, seconds);
      phase.surveillance = surv_watch.Figures(surveillance.Stats().bytes - surv_bytes, seconds);
      const double half_s = half_start != 0 ? NsToS(phase_stop - half_start) : 0.0;
      if (half_s > 0) {
        phase.pilot.settled_kbps =
            static_cast<double>(link.video().Stats().bytes - pilot_half_bytes) * 8e-3 / half_s;
        phase.surveillance.settled_kbps =
            static_cast<double>(surveillance.Stats().bytes - surv_half_bytes) * 8e-3 / half_s;
      }
      if (share_samples > 0) {
        phase.pilot.target_kbps = pilot_share_sum / share_samples;
        phase.surveillance.target_kbps = surv_share_sum / share_samples;
      }
      const std::vector<double> phase_aims(aim_latencies.begin() + static_cast<long>(aims_before),
                                           aim_latencies.end());
      phase.aims_shown = static_cast<int>(phase_aims.size());
      phase.aim_latency_ms_p50 = Percentile(phase_aims, 0.5);
      phase.aim_latency_ms_p95 = Percentile(phase_aims, 0.95);
      result.phases.push_back(phase);
      if (!link.ProcessAlive())
        throw std::runtime_error("haptel-vehicle ended: " + link.ExitDescription());
    }
    link.Stop();
    // The receivers start at their estimate's top (20 Mbit/s) until the
    // delay trend first says overuse: shares are drawn up to 1.5 times the
    // largest capacity, so the rates stay readable.
    const double top =
        1.5 * *std::max_element(options.capacities_kbps.begin(), options.capacities_kbps.end());
    for (Series* share : {&pilot_share_series, &surv_share_series}) {
      for (double& y : share->y) y = std::min(y, top);
    }
    PlotLines(options.out_dir / "video_cameras.png",
              {capacity_series, pilot_series, surv_series, pilot_share_series, surv_share_series},
              {"two cameras, one link: rates and shares (shares cut at 1.5x the top)", "time, s",
               "kbit/s"});
    result.head_mouse = head.Mouse();
    result.head_gamepad = head.Gamepad();
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
  csv << "phase,capacity_kbps,camera,fps,kbps,settled_kbps,share_kbps,latency_ms_p50,"
         "latency_ms_p95,aim_latency_ms_p50,aim_latency_ms_p95\n";
  for (size_t i = 0; i < result.phases.size(); ++i) {
    const TwoCameraPhase& p = result.phases[i];
    for (const auto& [name, f] :
         {std::pair{"pilot", p.pilot}, std::pair{"surveillance", p.surveillance}}) {
      const bool aimed = name == std::string("surveillance") && p.aims_shown > 0;
      csv << i + 1 << ',' << p.capacity_kbps << ',' << name << ',' << f.fps << ',' << f.kbps << ','
          << f.settled_kbps << ',' << f.target_kbps << ',' << f.latency_ms_p50 << ','
          << f.latency_ms_p95 << ',' << (aimed ? std::to_string(p.aim_latency_ms_p50) : "") << ','
          << (aimed ? std::to_string(p.aim_latency_ms_p95) : "") << '\n';
    }
  }
  return result;
}

}  // namespace haptel::bench
