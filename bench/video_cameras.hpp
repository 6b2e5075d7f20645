#pragma once
/// @file `haptel bench video`, part 3: a vehicle with two cameras through a
/// link whose capacity changes (issue 38). The thesis's blimp
/// (config/vehicles/sim-blimp-surveillance.yaml: the pilot's camera and the
/// surveillance camera, each its own stream) runs as a real haptel-vehicle
/// process; this side receives both streams on one participant, whose fault
/// line sets the capacity they share (as part 2's schedule does), and aims
/// the surveillance camera with CameraCommands: a new pan and zoom every
/// 0.5 s, and the command-to-picture latency is from a command's sending to
/// the first decoded frame carrying its seq (VideoFrame.command_seq; one
/// host, one clock). Per phase and camera: pictures per second, kbit/s,
/// capture-to-decoded latency p50/p95, the rate over the phase's second
/// half (settled: after the estimate's adaptation) and the vehicle's share
/// as its CameraStatus says it (video::LinkShare: the pilot's first, the
/// surveillance camera what it leaves, at least 150 kbit/s); the aim's
/// command-to-picture latency per phase. A trace every 0.5 s of each
/// camera's rate and share, video_cameras_trace.csv and video_cameras.png.
#include <filesystem>
#include <string>
#include <vector>

namespace haptel::bench {

struct CameraPhaseFigures {
  double fps = 0.0;
  double kbps = 0.0;
  double latency_ms_p50 = 0.0;
  double latency_ms_p95 = 0.0;
  double settled_kbps = 0.0;  ///< over the phase's second half
  double target_kbps = 0.0;   ///< the vehicle's share for it, mean over the second half (0: none)
};

struct TwoCameraPhase {
  double capacity_kbps = 0.0;
  CameraPhaseFigures pilot;
  CameraPhaseFigures surveillance;
  /// The surveillance camera's aim, command to the first picture showing it, ms.
  double aim_latency_ms_p50 = 0.0;
  double aim_latency_ms_p95 = 0.0;
  int aims_shown = 0;
};

/// The pilot's camera turned by a head source (view/head_source.hpp): from
/// the head's motion (a mouse drag, the stick pushed) to the first decoded
/// pilot picture whose command_seq is the first command carrying the new
/// pan, ms.
struct HeadLatency {
  double ms_p50 = 0.0;
  double ms_p95 = 0.0;
  int moves = 0;  ///< head motions made
  int shown = 0;  ///< of which a picture came
};

struct TwoCameraResult {
  std::vector<TwoCameraPhase> phases;
  /// Command to the first picture showing it, over the whole schedule, ms.
  double aim_latency_ms_p50 = 0.0;
  double aim_latency_ms_p95 = 0.0;
  int aims = 0;        ///< aim changes sent
  int aims_shown = 0;  ///< of which a picture came
  /// Meanwhile the pilot's head moves every 0.5 s, by the mouse and the
  /// game controller's stick in turn, through the same link.
  HeadLatency head_mouse;
  HeadLatency head_gamepad;
  bool ok = false;  ///< both cameras sent pictures in every phase
  std::string error;
};

struct TwoCameraOptions {
  std::vector<double> capacities_kbps{3000.0, 1500.0, 800.0, 3000.0};
  double phase_s = 15.0;
  int domain = 0;
  std::filesystem::path vehicle_file;  ///< a vehicle with a "surveillance" camera
  std::filesystem::path out_dir;       ///< video_cameras.csv, _trace.csv and .png go here
};

TwoCameraResult RunTwoCameraSchedule(const TwoCameraOptions& options);

}  // namespace haptel::bench
