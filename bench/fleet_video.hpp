#pragma once
/// @file `haptel bench fleet`'s video (issue 40): what each vehicle of a
/// fleet sends and what the operator shows of it, with a window.
///
/// N real haptel-vehicle processes (the fleet's first vehicle file, each
/// under a name of its own) play a lossless recording of the synthetic
/// camera's lap frames as their file camera, through their own codec, on
/// loopback with no link fault. In this process, as `haptel run --fleet`
/// has them, a VehicleLink per vehicle decodes its video and a SessionView
/// draws the fleet (a window on $DISPLAY, offscreen without one): the
/// first vehicle on the big screen (driven), every vehicle on its tile.
/// The others are tiles only and ask for a preview (VideoReceiver::
/// ShowAsTile), unless `previews` is off (the figure before it: every
/// vehicle at full size and rate). Not in it: the servo loop, the physics
/// and the interfaces of a run (`haptel run --fleet`'s own figures above).
///
/// After a warm-up (the vehicles up, the previews begun), per vehicle over
/// `seconds`: the video's kbit/s as received, the rate estimate sent to the
/// vehicle (the last and the least, sampled 10 times a second), its cuts,
/// the pictures decoded per second and their size, and SSIM of sampled
/// pictures (3 a second) against the frames they came from, at the size
/// they arrive (a tile's preview against its source scaled down).
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace haptel::bench {

struct FleetVideoVehicle {
  std::string name;
  bool driven = false;  ///< on the big screen; the others are tiles
  double kbps = 0.0;
  double target_kbps = 0.0;      ///< the last estimate sent to the vehicle
  double target_kbps_min = 0.0;  ///< the least over the measurement
  uint64_t rate_cuts = 0;
  double fps = 0.0;  ///< pictures decoded per second
  int width = 0, height = 0;
  double ssim = 0.0;  ///< NaN: no sample
  int ssim_samples = 0;
};

struct FleetVideoCount {
  int vehicles = 0;
  bool ran = false;
  std::string error;
  std::vector<FleetVideoVehicle> vehicle;
  std::string view_mode;  ///< "window" or "offscreen"
  double view_fps = 0.0;
};

struct FleetVideoOptions {
  std::filesystem::path vehicle_file;  ///< the fleet's first vehicle
  std::filesystem::path track_file;    ///< its world
  std::filesystem::path out_dir;       ///< the source and vehicle files go here
  int domain = 0;
  double warm_up_s = 3.0;
  double seconds = 15.0;
  bool previews = true;  ///< tiles ask for previews (false: every vehicle at full size)
};

/// `frames`: the source the vehicles play (looped at their camera's rate).
/// Never throws: a count that could not run says why in `error`.
FleetVideoCount MeasureFleetVideo(int count, const std::vector<cv::Mat>& frames,
                                  const FleetVideoOptions& options);

}  // namespace haptel::bench
