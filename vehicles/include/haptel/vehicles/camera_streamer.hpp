#pragma once
/// @file A vehicle's camera on the link: grabs frames from its source at
/// `camera.rate_hz` on a thread of its own, JPEG-encodes them and publishes
/// them on haptel/<vehicle>/video — so a slow or stalled camera never delays
/// a control loop or its watchdog. Any vehicle node has one.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/codec.hpp"

namespace haptel::vehicles {

struct CameraCounters {
  uint64_t frames_published = 0;
  uint64_t frames_failed = 0;  ///< grabbed but not encoded
  uint64_t grabs_failed = 0;   ///< the camera source delivered no frame
  uint64_t camera_stalls = 0;  ///< stretches of failed grabs long enough to count (GrabMonitor)
  bool camera_ended = false;   ///< a file source that does not loop has ended
};

class CameraStreamer {
 public:
  /// `camera` must not be null; `participant` must outlive the streamer.
  CameraStreamer(const CameraConfig& config, std::unique_ptr<video::CameraSource> camera,
                 link::Participant& participant, const std::string& vehicle_name);
  ~CameraStreamer();
  CameraStreamer(const CameraStreamer&) = delete;
  CameraStreamer& operator=(const CameraStreamer&) = delete;

  void Start();
  void Stop();
  /// Where the camera is now (any thread; a synthetic source renders from it).
  void SetPose(const video::CameraPose& pose) { pose_.Store(pose); }
  CameraCounters Counters() const;

 private:
  void Tick(int64_t now_ns);

  std::unique_ptr<video::CameraSource> camera_;
  Seqlock<video::CameraPose> pose_;
  video::GrabMonitor grab_monitor_;
  bool end_reported_ = false;
  video::JpegEncoder encoder_;
  cv::Mat image_;
  msg::VideoFrame frame_msg_;
  std::vector<uint8_t> jpeg_;
  uint64_t frame_seq_ = 0;
  std::atomic<uint64_t> frames_{0}, frames_failed_{0}, grabs_failed_{0}, camera_stalls_{0};
  std::atomic<bool> camera_ended_{false};
  link::VideoWriter writer_;
  std::unique_ptr<PeriodicThread> loop_;
};

}  // namespace haptel::vehicles
