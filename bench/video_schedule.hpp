#pragma once
/// @file `haptel bench video`, part 2: the video through a link whose
/// capacity changes (issue 24, after RFC 8867's variable-capacity test).
///
/// A real haptel-vehicle process streams a lossless recording of the
/// synthetic camera's lap frames (part 1's frames, written as an FFV1 file
/// and played by the vehicle's file camera, looping) through the fault
/// transport, while the link's rate steps 2.0 -> 1.0 -> 1.75 -> 0.5 ->
/// 1.0 Mbit/s. The rate stage is changed at run time on the operator's own
/// fault line (link::FaultLine::SetRate): the fault is applied to what each
/// process receives, so the operator's line alone sets the rate the video
/// arrives at; the vehicle's line, which its commands and the feedback pass,
/// stays at the first phase's rate. Nothing crosses processes to change it
/// (no control topic, no file watched): the product path is untouched.
///
/// Commands go at 100 Hz meanwhile (a gentle back-and-forth). Per phase:
/// the video's bitrate as received, SSIM of decoded pictures against their
/// source frames (a sample of about 3 a second; the source frame is found
/// from the capture stamp and the frame rate, confirmed by the nearest
/// picture among its neighbours), capture-to-decoded latency p50/p95 (as the
/// view gets the pictures), frames lost, time stale, and the command round
/// trip p99. `adapt_s`: the longest time, over the steps down, from the
/// step until the latency p95 over a trailing 1 s window is back under
/// 150 ms (0 when it never went over; the phase's length when it never came
/// back).
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/vehicle_link.hpp"

namespace haptel::bench {

struct SchedulePhase {
  double capacity_kbps = 0.0;
  double video_kbps = 0.0;
  double target_kbps = 0.0;  ///< the estimator's last target in the phase
  double ssim = 0.0;         ///< mean over the sampled pictures (NaN: none)
  int ssim_samples = 0;
  double fps = 0.0;  ///< pictures decoded per second
  double latency_ms_p50 = 0.0;
  double latency_ms_p95 = 0.0;
  uint64_t frames_lost = 0;
  double stale_s = 0.0;
  double command_rtt_ms_p99 = 0.0;
  double adapt_s = 0.0;  ///< after a step down; 0 otherwise
  bool step_down = false;
};

struct ScheduleResult {
  CameraCodec codec = CameraCodec::kJpeg;
  std::vector<SchedulePhase> phases;
  double adapt_s = 0.0;  ///< the longest over the steps down
  bool ok = false;       ///< the vehicle came up and sent video throughout
  std::string error;
};

struct ScheduleOptions {
  std::vector<double> capacities_kbps{2000.0, 1000.0, 1750.0, 500.0, 1000.0};
  double phase_s = 25.0;
  int domain = 0;
  std::filesystem::path out_dir;  ///< the source file, the vehicle file, CSV and PNG go here
  std::filesystem::path track_file;
};

/// Runs the schedule with `vehicle`'s camera (its codec replaced by `codec`),
/// streaming `frames` (the source, looped at the camera's rate). Writes
/// video_schedule_<codec>.csv (the phases) and video_schedule_<codec>_trace.csv,
/// video_schedule_<codec>.png (capacity, target and bitrate against time;
/// latency under it) into options.out_dir.
ScheduleResult RunCapacitySchedule(const VehicleConfig& vehicle, CameraCodec codec,
                                   const std::vector<cv::Mat>& frames,
                                   const ScheduleOptions& options);

/// The operator's side of a capacity schedule: `vehicle` spawned as
/// haptel-vehicle on `domain` (`track_file` its world), its video decoded, the
/// link behind a fault line that starts at `first_kbps` (each phase then
/// steps it with FaultLine::SetRate).
mediator::VehicleLinkOptions ScheduleLinkOptions(VehicleConfig vehicle, int domain,
                                                 double first_kbps,
                                                 std::filesystem::path track_file);

}  // namespace haptel::bench
