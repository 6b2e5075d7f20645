#include "haptel/video/video_receiver.hpp"

#include <pthread.h>

#include <chrono>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "haptel/core/clock.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/link/families.hpp"
#include "haptel/video/h264_codec.hpp"

namespace haptel::video {
namespace {

/// H.264 frames waiting for the decoder beyond this are dropped, all of them
/// (the decoder is that far behind: better a key frame than old pictures).
constexpr size_t kMaxQueuedH264 = 15;
/// The decoder thread wakes at least this often to check for a silent link.
constexpr auto kSilenceCheck = std::chrono::milliseconds(100);

}  // namespace

cv::Mat MarkStale(const cv::Mat& picture) {
  cv::Mat marked = picture.clone();
  const int border = std::max(2, marked.cols / 80);
  const cv::Scalar red(0, 0, 255);
  cv::rectangle(marked, cv::Rect(0, 0, marked.cols, marked.rows), red, 2 * border);
  const double scale = std::max(0.5, marked.cols / 640.0);
  cv::putText(marked, "STALE", cv::Point(3 * border, 3 * border + static_cast<int>(24 * scale)),
              cv::FONT_HERSHEY_SIMPLEX, scale, red, std::max(1, static_cast<int>(2 * scale)),
              cv::LINE_AA);
  return marked;
}

VideoReceiver::VideoReceiver() : decode_(false) {}

VideoReceiver::VideoReceiver(link::Participant& participant, const std::string& vehicle,
                             uint64_t session, bool decode, const std::string& camera,
                             FrameObserver on_frame)
    : decode_(decode),
      session_(session),
      on_frame_(std::move(on_frame)),
      feedback_(std::make_unique<link::VideoFeedbackWriter>(
          participant, link::VideoFeedbackTopic(vehicle, camera, camera.empty()),
          link::Profile::kState)) {
  decoder_thread_ = std::thread([this] { DecodeLoop(); });
  reader_ = std::make_unique<link::VideoReader>(
      participant, link::VideoTopic(vehicle, camera, camera.empty()), link::Profile::kVideo,
      [this](const msg::VideoFrame& f, const link::SampleStamps& stamps) { OnFrame(f, stamps); });
  std::lock_guard lock(mutex_);
  reader_ready_ = true;
}

VideoReceiver::~VideoReceiver() {
  {
    std::lock_guard lock(mutex_);
    reader_ready_ = false;  // the decoder thread no longer asks it
  }
  reader_.reset();
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  ready_.notify_all();
  if (decoder_thread_.joinable()) decoder_thread_.join();
}

void VideoReceiver::OnFrame(const msg::VideoFrame& frame, const link::SampleStamps& stamps) {
  if (on_frame_) on_frame_(frame, stamps);
  const int64_t now = stamps.arrived_ns;
  const bool h264 = frame.encoding() == CameraCodecName(CameraCodec::kH264);
  msg::VideoFeedback rate;  // sent below when the estimate is due
  bool rate_due = false;
  {
    std::lock_guard lock(mutex_);
    // The link's rate from this frame's arrival against its sending (only
    // differences of each: the clocks need not agree), both stamped on the
    // link's threads: neither the vehicle's encoding nor this side's
    // decoding is in the delay.
    estimator_.OnFrame(frame.seq(), NsToS(stamps.sent_ns), NsToS(now), frame.data().size());
    if (estimator_.FeedbackDue(NsToS(now))) {
      rate_due = true;
      rate = RateFeedback(now, frame.seq());
    }
    total_bytes_ += frame.data().size();
    if (first_arrival_ns_ == 0) {
      first_arrival_ns_ = now;
    } else {
      bytes_ += frame.data().size();
    }
    last_arrival_ns_ = now;
    if (last_seq_ != 0 && frame.seq() > last_seq_ + 1) frames_lost_ += frame.seq() - last_seq_ - 1;
    if (frame.seq() > last_seq_) last_seq_ = frame.seq();
    if (frame.key_frame()) ++key_frames_;
    // JPEG: the latest wins. H.264: every frame, in order (a bounded queue).
    if (!pending_.empty() &&
        (!h264 || !pending_.back().h264 || pending_.size() >= kMaxQueuedH264)) {
      dropped_ += pending_.size();
      for (Pending& p : pending_) spare_.push_back(std::move(p.bytes));
      pending_.clear();
    }
    Pending p;
    if (!spare_.empty()) {
      p.bytes = std::move(spare_.back());
      spare_.pop_back();
    }
    p.bytes.assign(frame.data().begin(), frame.data().end());
    p.capture_ns = frame.capture_wall_ns();
    p.seq = frame.seq();
    p.command_seq = frame.command_seq();
    p.zoom = frame.zoom();
    p.key_frame = frame.key_frame();
    p.h264 = h264;
    pending_.push_back(std::move(p));
  }
  ready_.notify_one();
  if (rate_due) feedback_->Write(rate);
}

msg::VideoFeedback VideoReceiver::RateFeedback(int64_t now_ns, uint64_t last_frame_seq) {
  msg::VideoFeedback rate;
  target_kbps_sent_ = estimator_.target_kbps();
  rate.seq(++feedback_seq_);
  rate.session(session_);
  rate.sent_ns(now_ns);
  rate.key_frame_request(false);
  rate.last_frame_seq(last_frame_seq);
  rate.target_kbps(static_cast<uint32_t>(target_kbps_sent_));
  rate.preview(tile_);
  return rate;
}

void VideoReceiver::ShowAsTile(bool tile) {
  if (!feedback_) return;
  msg::VideoFeedback said;
  {
    std::lock_guard lock(mutex_);
    if (tile == tile_) return;
    tile_ = tile;
    said.seq(++feedback_seq_);
    said.session(session_);
    said.sent_ns(MonotonicNs());
    said.key_frame_request(false);
    said.last_frame_seq(last_seq_);
    said.target_kbps(static_cast<uint32_t>(target_kbps_sent_));
    said.preview(tile_);
  }
  feedback_->Write(said);
}

void VideoReceiver::CheckSilence(int64_t now_ns) {
  msg::VideoFeedback rate;
  {
    std::lock_guard lock(mutex_);
    // Only while a vehicle publishes video: without one, silence says nothing of the link.
    if (!reader_ready_ || reader_->matched() == 0) return;
    if (!estimator_.OnSilence(NsToS(now_ns)) || !estimator_.FeedbackDue(NsToS(now_ns))) return;
    rate = RateFeedback(now_ns, last_seq_);
  }
  if (feedback_) feedback_->Write(rate);
}

void VideoReceiver::RequestKeyFrameIfDue(int64_t now_ns) {
  if (last_request_ns_ != 0 && now_ns - last_request_ns_ < kKeyFrameRequestPeriodNs) return;
  last_request_ns_ = now_ns;
  msg::VideoFeedback request;
  request.sent_ns(now_ns);
  request.session(session_);
  request.key_frame_request(true);
  {
    std::lock_guard lock(mutex_);
    request.seq(++feedback_seq_);
    request.last_frame_seq(last_seq_);
    request.target_kbps(static_cast<uint32_t>(target_kbps_sent_));
    request.preview(tile_);
    ++key_frame_requests_;
  }
  feedback_->Write(request);
}

bool VideoReceiver::DecodeOne(Pending& frame, cv::Mat& image) {
  const CameraCodec codec = frame.h264 ? CameraCodec::kH264 : CameraCodec::kJpeg;
  if (decoder_ == nullptr || decoder_->codec() != codec) decoder_ = MakeVideoDecoder(codec);
  const DecodeResult result = decoder_->DecodeFrame(
      {frame.bytes.data(), frame.bytes.size(), frame.seq, frame.key_frame}, image);
  if (result == DecodeResult::kPicture) return true;
  std::lock_guard lock(mutex_);
  if (result == DecodeResult::kCorrupt) ++decode_failures_;
  // A frame after a gap is as undecodable as one while a key frame is awaited.
  if (result == DecodeResult::kAwaitingKeyFrame || result == DecodeResult::kLost) ++frames_skipped_;
  return false;
}

void VideoReceiver::DecodeLoop() {
  // Decoding takes milliseconds of CPU a frame: behind the link's receive
  // threads, which carry the states, and the session's loop on a busy host.
  LowerThreadPriority(kBackgroundNiceSteps);
  pthread_setname_np(pthread_self(),
                     "video-decode");  // named once lowered: what a test may wait for
  std::deque<Pending> batch;
  cv::Mat image;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      // While a key frame is awaited, wake at the request period even when
      // no frame comes: the request is repeated until one does.
      const auto waiting = [this] { return stop_ || !pending_.empty(); };
      if (decoder_ != nullptr && decoder_->awaiting_key_frame() && decode_) {
        ready_.wait_for(lock, std::chrono::nanoseconds(kKeyFrameRequestPeriodNs), waiting);
      } else {
        ready_.wait_for(lock, kSilenceCheck, waiting);
      }
      if (stop_) return;
      if (pending_.empty()) {
        // Woken by the period, not by a frame: is the link silent?
        lock.unlock();
        CheckSilence(MonotonicNs());
        lock.lock();
        if (stop_) return;
      }
      for (Pending& b : batch) spare_.push_back(std::move(b.bytes));
      batch.clear();
      batch.swap(pending_);
    }
    bool shown_any = false;
    int64_t capture_ns = 0, decoded_wall_ns = 0;
    uint64_t command_seq = 0;
    float zoom = 1.0F;
    for (Pending& frame : batch) {
      if (decode_ && !DecodeOne(frame, image)) continue;
      shown_any = true;
      capture_ns = frame.capture_ns;
      command_seq = frame.command_seq;
      zoom = frame.zoom;
      const int64_t now_wall = WallNs();
      decoded_wall_ns = now_wall;
      std::lock_guard lock(mutex_);
      latency_.Record(static_cast<double>(now_wall - frame.capture_ns) * 1e-3);
      const int64_t now = MonotonicNs();
      if (frames_++ == 0) first_frame_ns_ = now;
      last_frame_ns_ = now;
      // Kept as it came (a swap: the buffers go round, nothing is copied here):
      // a JPEG frame, or without a screen an H.264 key frame (a thumbnail
      // decodes it when asked; delta frames cannot be decoded alone).
      if (!frame.h264) {
        last_bytes_.swap(frame.bytes);
        last_key_bytes_.clear();
      } else {
        last_bytes_.clear();
        if (!decode_ && frame.key_frame) last_key_bytes_.swap(frame.bytes);
      }
    }
    const int64_t now = MonotonicNs();
    if (!decode_) continue;
    if (shown_any) {
      // A fresh image per picture: whoever holds the previous one keeps it intact.
      auto shown = std::make_shared<const cv::Mat>(image.clone());
      std::lock_guard lock(mutex_);
      if (stale_since_ns_ != 0) stale_ns_ += now - stale_since_ns_;
      stale_since_ns_ = 0;
      latest_good_ = shown;
      latest_ = {std::move(shown), latest_.id + 1, capture_ns, false,
                 decoded_wall_ns,  command_seq,    zoom};
    }
    if (decoder_ != nullptr && decoder_->awaiting_key_frame()) {
      // Stale only once a picture was shown: before the first there is none
      // to mark. Marked outside the lock: this thread runs at a low priority,
      // and the link's receive thread (the states') must never wait on it
      // for longer than a copy of a few fields.
      std::shared_ptr<const cv::Mat> good;
      {
        std::lock_guard lock(mutex_);
        if (stale_since_ns_ == 0) good = latest_good_;
      }
      if (good) {
        auto marked = std::make_shared<const cv::Mat>(MarkStale(*good));
        std::lock_guard lock(mutex_);
        stale_since_ns_ = now;
        latest_ = {std::move(marked),
                   latest_.id + 1,
                   latest_.capture_wall_ns,
                   true,
                   latest_.decoded_wall_ns,
                   latest_.command_seq,
                   latest_.zoom};
      }
      RequestKeyFrameIfDue(now);
    }
  }
}

VideoStats VideoReceiver::Stats() const {
  const int64_t now = MonotonicNs();
  std::lock_guard lock(mutex_);
  VideoStats s;
  s.frames = frames_;
  s.dropped = dropped_;
  s.decode_failures = decode_failures_;
  s.frames_lost = frames_lost_;
  s.frames_skipped = frames_skipped_;
  s.key_frame_requests = key_frame_requests_;
  s.key_frames = key_frames_;
  const double span = NsToS(last_frame_ns_ - first_frame_ns_);
  s.fps = frames_ > 1 && span > 0 ? static_cast<double>(frames_ - 1) / span : 0.0;
  s.latency_ms_p50 = latency_.Percentile(0.5) * 1e-3;
  s.latency_ms_p99 = latency_.Percentile(0.99) * 1e-3;
  const double arrivals = NsToS(last_arrival_ns_ - first_arrival_ns_);
  s.bytes = total_bytes_;
  s.kbps = arrivals > 0 ? static_cast<double>(bytes_) * 8.0 / arrivals / 1000.0 : 0.0;
  s.stale_s = NsToS(stale_ns_ + (stale_since_ns_ != 0 ? now - stale_since_ns_ : 0));
  s.target_kbps = target_kbps_sent_;
  s.rate_cuts = estimator_.decreases();
  s.tile = tile_;
  return s;
}

std::vector<uint8_t> VideoReceiver::LatestPicture() const {
  std::shared_ptr<const cv::Mat> picture;
  std::vector<uint8_t> key_frame;
  {
    std::lock_guard lock(mutex_);
    if (!last_bytes_.empty()) return last_bytes_;
    picture = latest_good_;
    if (!picture) key_frame = last_key_bytes_;
  }
  std::vector<uint8_t> jpeg;
  if (!picture && !key_frame.empty()) {
    // No screen, so no decoder running: the last key frame decodes alone.
    H264Decoder decoder;
    cv::Mat image;
    if (decoder.DecodeFrame({key_frame.data(), key_frame.size(), 1, true}, image) ==
        DecodeResult::kPicture) {
      picture = std::make_shared<const cv::Mat>(std::move(image));
    }
  }
  if (picture) JpegEncoder(80).Encode(*picture, jpeg);
  return jpeg;
}

Frame VideoReceiver::Latest() const {
  std::lock_guard lock(mutex_);
  return latest_;
}

}  // namespace haptel::video
