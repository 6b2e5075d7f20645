#include "haptel/vehicles/camera_streamer.hpp"

#include <stdexcept>

#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"

namespace haptel::vehicles {

CameraStreamer::CameraStreamer(const CameraConfig& config, std::unique_ptr<video::CameraSource> camera,
                               link::Participant& participant, const std::string& vehicle_name)
    : camera_(std::move(camera)),
      encoder_(config.jpeg_quality),
      writer_(participant, link::TopicName(vehicle_name, "video"), link::Profile::kVideo) {
  if (camera_ == nullptr) throw std::invalid_argument("CameraStreamer: no camera source");
  loop_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-camera", .rate_hz = config.rate_hz},
      [this](int64_t now) { Tick(now); });
}

CameraStreamer::~CameraStreamer() { Stop(); }

void CameraStreamer::Start() { loop_->Start(); }
void CameraStreamer::Stop() { loop_->Stop(); }

void CameraStreamer::Tick(int64_t now_ns) {
  if (camera_->Ended()) {
    // The vehicle stays controllable; it just has no more video to send.
    if (!end_reported_) {
      end_reported_ = true;
      camera_ended_.store(true);
      log::Warn("camera file ended (" + camera_->Describe() +
                "); no more video is published, the vehicle stays controllable");
    }
    return;
  }
  const video::CameraPose pose = pose_.Load();
  const int64_t before_grab_wall_ns = WallNs();
  const bool grabbed = camera_->Grab(pose, image_);
  // A device's Grab may wait up to a frame period for the frame: it exists
  // when Grab returns. A rendered frame shows the pose read before Grab.
  const int64_t capture_wall_ns = camera_->RendersAtGrab() ? before_grab_wall_ns : WallNs();
  if (!grabbed && camera_->Ended()) return;  // an end, not a failure: reported next tick
  if (grab_monitor_.OnGrab(grabbed, now_ns) == video::GrabMonitor::Event::kStalled) {
    log::Warn("camera " + camera_->Describe() + " delivers no frames (" +
              std::to_string(grab_monitor_.failures_in_a_row()) +
              " grabs in a row failed); the vehicle runs on without video (reported once; "
              "counted in the stop summary)");
  }
  grabs_failed_.store(grab_monitor_.failures(), std::memory_order_relaxed);
  camera_stalls_.store(grab_monitor_.stalls(), std::memory_order_relaxed);
  if (!grabbed) return;
  if (!encoder_.Encode(image_, jpeg_)) {
    frames_failed_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  msg::VideoFrame& f = frame_msg_;
  f.seq(++frame_seq_);
  f.capture_wall_ns(capture_wall_ns);
  f.width(static_cast<uint16_t>(image_.cols));
  f.height(static_cast<uint16_t>(image_.rows));
  f.encoding("jpeg");
  f.data().assign(jpeg_.begin(), jpeg_.end());
  writer_.Write(f);
  frames_.fetch_add(1, std::memory_order_relaxed);
}

CameraCounters CameraStreamer::Counters() const {
  CameraCounters c;
  c.frames_published = frames_.load();
  c.frames_failed = frames_failed_.load();
  c.grabs_failed = grabs_failed_.load();
  c.camera_stalls = camera_stalls_.load();
  c.camera_ended = camera_ended_.load();
  return c;
}

}  // namespace haptel::vehicles
