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

/// Which commands a vehicle takes: newer sequence numbers only, since
/// best-effort delivery may reorder — unless the sender restarted (its
/// sequence began again) and the last accepted command is older than the
/// watchdog timeout. Called from the DDS thread only.
class CommandSequence {
 public:
  explicit CommandSequence(double restart_after_s) : restart_after_ns_(static_cast<int64_t>(restart_after_s * 1e9)) {}
  /// True (and remembered) when `seq` received at `now_ns` is to be applied.
  bool Accept(uint64_t seq, int64_t now_ns) {
    const bool restarted = now_ns - last_ns_ > restart_after_ns_;
    if (seq <= last_seq_ && !restarted) return false;
    last_seq_ = seq;
    last_ns_ = now_ns;
    return true;
  }

 private:
  int64_t restart_after_ns_;
  uint64_t last_seq_ = 0;
  int64_t last_ns_ = 0;
};

}  // namespace haptel::vehicles
