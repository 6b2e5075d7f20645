#include "haptel/mediator/video_receiver.hpp"

#include "haptel/core/clock.hpp"

namespace haptel::mediator {

VideoReceiver::VideoReceiver(link::Participant& participant, const std::string& topic, bool decode)
    : decode_(decode) {
  decoder_thread_ = std::thread([this] { DecodeLoop(); });
  reader_ = std::make_unique<link::VideoReader>(participant, topic, link::Profile::kVideo,
                                                [this](const msg::VideoFrame& f) { OnFrame(f); });
}

VideoReceiver::~VideoReceiver() {
  reader_.reset();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  ready_.notify_all();
  decoder_thread_.join();
}

void VideoReceiver::OnFrame(const msg::VideoFrame& frame) {
  {
    std::lock_guard lock(mutex_);
    if (has_pending_) ++dropped_;
    pending_.assign(frame.data().begin(), frame.data().end());
    pending_capture_ns_ = frame.capture_wall_ns();
    has_pending_ = true;
  }
  ready_.notify_one();
}

void VideoReceiver::DecodeLoop() {
  std::vector<uint8_t> bytes;
  cv::Mat image;
  for (;;) {
    int64_t capture_ns = 0;
    {
      std::unique_lock lock(mutex_);
      ready_.wait(lock, [this] { return stop_ || has_pending_; });
      if (stop_) return;
      bytes.swap(pending_);
      capture_ns = pending_capture_ns_;
      has_pending_ = false;
    }
    if (decode_ && !decoder_.Decode(bytes.data(), bytes.size(), image)) {
      std::lock_guard lock(mutex_);
      ++decode_failures_;
      continue;
    }
    const int64_t now_wall = WallNs();
    const int64_t now = MonotonicNs();
    // A fresh image per frame: whoever holds the previous one keeps it intact.
    std::shared_ptr<const cv::Mat> shown = decode_ ? std::make_shared<const cv::Mat>(image.clone()) : nullptr;
    std::lock_guard lock(mutex_);
    if (decode_) latest_ = {std::move(shown), latest_.id + 1, capture_ns};
    // Kept as it came (a swap: the buffers go round, nothing is copied here).
    last_bytes_.swap(bytes);
    latency_.Record(static_cast<double>(now_wall - capture_ns) * 1e-3);
    if (frames_++ == 0) first_frame_ns_ = now;
    last_frame_ns_ = now;
  }
}

VideoStats VideoReceiver::Stats() const {
  std::lock_guard lock(mutex_);
  VideoStats s;
  s.frames = frames_;
  s.dropped = dropped_;
  s.decode_failures = decode_failures_;
  const double span = NsToS(last_frame_ns_ - first_frame_ns_);
  s.fps = frames_ > 1 && span > 0 ? static_cast<double>(frames_ - 1) / span : 0.0;
  s.latency_ms_p50 = latency_.Percentile(0.5) * 1e-3;
  s.latency_ms_p99 = latency_.Percentile(0.99) * 1e-3;
  return s;
}

cv::Mat VideoReceiver::Screen() const {
  const LatestFrame latest = Latest();
  return latest.image ? latest.image->clone() : cv::Mat();
}

std::vector<uint8_t> VideoReceiver::LatestPicture() const {
  std::lock_guard lock(mutex_);
  return last_bytes_;
}

LatestFrame VideoReceiver::Latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

}  // namespace haptel::mediator
