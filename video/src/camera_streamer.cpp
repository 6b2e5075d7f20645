#include "haptel/video/camera_streamer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/link/families.hpp"
#include "haptel/video/h264_codec.hpp"

namespace haptel::video {

namespace {

/// Half `size`, even (H.264's 4:2:0 needs it) and at least 16.
int HalfEven(int size) { return std::max(16, size / 2 / 2 * 2); }

CameraConfig PreviewConfig(const CameraConfig& full) {
  CameraConfig c = full;
  c.width = HalfEven(full.width);
  c.height = HalfEven(full.height);
  c.rate_hz = std::min(full.rate_hz, CameraStreamer::kPreviewRate_hz);
  // A quarter of the pixels at a third of the frames: the full bitrate's
  // share of them, at least the encoder's least.
  c.bitrate_kbps =
      std::max(H264Encoder::kMinFollowKbps,
               static_cast<int>(full.bitrate_kbps / 4.0 * std::min(1.0, c.rate_hz / full.rate_hz)));
  return c;
}

}  // namespace

int LinkShare::Add(int priority, uint32_t most_kbps) {
  if (count_ >= kMaxSlots) throw std::invalid_argument("LinkShare: too many cameras");
  const int slot = count_++;
  slots_[static_cast<size_t>(slot)].priority = priority;
  slots_[static_cast<size_t>(slot)].most_kbps = most_kbps;
  // Kept in priority order; equal priorities in the order added.
  int at = slot;
  while (at > 0 &&
         slots_[static_cast<size_t>(order_[static_cast<size_t>(at - 1)])].priority > priority) {
    order_[static_cast<size_t>(at)] = order_[static_cast<size_t>(at - 1)];
    --at;
  }
  order_[static_cast<size_t>(at)] = slot;
  return slot;
}

void LinkShare::Split(uint32_t capacity_kbps, const Demand* demands, int count,
                      uint32_t* targets_kbps) {
  if (count <= 0) return;
  // A floor for each camera; an equal share when the link cannot hold them all.
  const uint64_t floor =
      std::min<uint64_t>(kFloor_kbps, capacity_kbps / static_cast<uint64_t>(count));
  uint64_t left = capacity_kbps;
  for (int i = 0; i < count; ++i) {
    const uint64_t reserved = floor * static_cast<uint64_t>(count - 1 - i);
    uint64_t given = left > reserved ? left - reserved : 0;
    if (demands[i].most_kbps > 0) given = std::min<uint64_t>(given, demands[i].most_kbps);
    given = std::max(given, std::min(floor, left));
    targets_kbps[i] = static_cast<uint32_t>(given);
    // What it takes of the link: what it was given, or, sending less (a
    // JPEG camera on its top rung), a margin over what it sends; the rest
    // is the next camera's. Its target is not cut to that margin: a
    // ladder's rungs lie below their target, and a target that followed
    // what was sent would ratchet down to the floor.
    uint64_t taken = given;
    if (demands[i].sent_kbps > 0) {
      taken = std::min<uint64_t>(
          given, static_cast<uint64_t>(kHeadroom * static_cast<double>(demands[i].sent_kbps)));
    }
    left -= std::min(left, taken);
  }
}

uint32_t LinkShare::CapacityKbps(int64_t now_ns) const {
  uint64_t sum = 0;
  for (int i = 0; i < count_; ++i) {
    const Slot& s = slots_[static_cast<size_t>(i)];
    if (Fresh(s, now_ns)) sum += s.estimate_kbps.load(std::memory_order_relaxed);
  }
  return static_cast<uint32_t>(std::min<uint64_t>(sum, std::numeric_limits<uint32_t>::max()));
}

void LinkShare::OnEstimate(int slot, uint32_t kbps, int64_t now_ns) {
  if (slot < 0 || slot >= count_ || kbps == 0) return;
  slots_[static_cast<size_t>(slot)].estimate_kbps.store(kbps, std::memory_order_relaxed);
  slots_[static_cast<size_t>(slot)].estimate_ns.store(now_ns, std::memory_order_relaxed);
}

void LinkShare::OnSent(int slot, size_t bytes, int64_t now_ns) {
  if (slot < 0 || slot >= count_) return;
  Slot& s = slots_[static_cast<size_t>(slot)];  // one camera thread per slot writes it
  const int64_t start = s.window_start_ns.load(std::memory_order_relaxed);
  if (now_ns - start >= 1'000'000'000) {
    // Two seconds or more since: the previous second sent nothing.
    s.bytes_before.store(now_ns - start >= 2'000'000'000 ? 0 : s.bytes_now.load(),
                         std::memory_order_relaxed);
    s.bytes_now.store(0, std::memory_order_relaxed);
    s.window_start_ns.store(now_ns, std::memory_order_relaxed);
  }
  s.bytes_now.fetch_add(bytes, std::memory_order_relaxed);
}

uint32_t LinkShare::SentKbps(int slot, int64_t now_ns) const {
  if (slot < 0 || slot >= count_) return 0;
  const Slot& s = slots_[static_cast<size_t>(slot)];
  const int64_t start = s.window_start_ns.load(std::memory_order_relaxed);
  if (now_ns - start >= 2'000'000'000) return 0;
  // The last whole second, or the part of this one when it is the first.
  const uint64_t before = s.bytes_before.load(std::memory_order_relaxed);
  const uint64_t now_bytes = s.bytes_now.load(std::memory_order_relaxed);
  const double seconds = before > 0 ? 1.0 : std::max(0.1, NsToS(now_ns - start));
  return static_cast<uint32_t>((before > 0 ? before : now_bytes) * 8.0 / 1000.0 / seconds);
}

uint32_t LinkShare::TargetFor(int slot, int64_t now_ns) const {
  if (slot < 0 || slot >= count_) return 0;
  if (!Fresh(slots_[static_cast<size_t>(slot)], now_ns)) return 0;
  // The watched cameras, in priority order.
  std::array<Demand, kMaxSlots> demands{};
  std::array<uint32_t, kMaxSlots> targets{};
  int watched = 0, mine = -1;
  for (int k = 0; k < count_; ++k) {
    const int i = order_[static_cast<size_t>(k)];
    const Slot& s = slots_[static_cast<size_t>(i)];
    if (!Fresh(s, now_ns)) continue;
    if (i == slot) mine = watched;
    demands[static_cast<size_t>(watched++)] = {s.most_kbps, SentKbps(i, now_ns)};
  }
  Split(CapacityKbps(now_ns), demands.data(), watched, targets.data());
  return targets[static_cast<size_t>(mine)];
}

CameraStreamer::CameraStreamer(const CameraConfig& config, std::unique_ptr<CameraSource> camera,
                               link::Participant& participant, const std::string& vehicle_name,
                               OwnerWriter owner_writer, bool driven, LinkShare* share)
    : config_(config),
      owner_writer_(std::move(owner_writer)),
      passthrough_possible_(config.codec == CameraCodec::kJpeg),
      camera_(std::move(camera)),
      encoder_(MakeVideoEncoder(config)),
      preview_config_(PreviewConfig(config)),
      codec_name_(CameraCodecName(config.codec)),
      share_(share),
      writer_(participant, link::VideoTopic(vehicle_name, config.name, driven),
              link::Profile::kVideo) {
  // H.264's encoder never goes over its configured bitrate; JPEG's ladder has no bound.
  if (share_ != nullptr) {
    share_slot_ = share_->Add(config.priority, config.codec == CameraCodec::kH264
                                                   ? static_cast<uint32_t>(config.bitrate_kbps)
                                                   : 0U);
  }
  frame_msg_.camera(config.name);
  if (camera_ == nullptr) throw std::invalid_argument("CameraStreamer: no camera source");
  if (!owner_writer_) throw std::invalid_argument("CameraStreamer: no owner writer");
  loop_ = std::make_unique<PeriodicThread>(
      // Rendering and encoding a frame takes milliseconds of CPU: behind the
      // control loop and the link's threads, so commands and states never
      // wait for it on a busy host.
      PeriodicThread::Options{
          .name = "vehicle-camera", .rate_hz = config.rate_hz, .nice_steps = kBackgroundNiceSteps},
      [this](int64_t now) { Tick(now); });
  // Reliable: a request is small and rare (at most ten a second, while the
  // operator waits), and one lost would leave the picture stale longer.
  feedback_ = std::make_unique<link::VideoFeedbackReader>(
      participant, link::VideoFeedbackTopic(vehicle_name, config.name, driven),
      link::Profile::kState,
      [this](const msg::VideoFeedback& f, const link::WriterId& sender) { OnFeedback(f, sender); });
}

void CameraStreamer::OnFeedback(const msg::VideoFeedback& feedback, const link::WriterId& sender) {
  // Only the owner's: another participant's target or key frame request
  // would hold the owner's video at a rung it did not ask for.
  if (!FeedbackFromOwner(owner_writer_(), sender)) {
    feedback_refused_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (feedback.target_kbps() > 0)
    target_kbps_.store(feedback.target_kbps(), std::memory_order_relaxed);
  if (share_ != nullptr) share_->OnEstimate(share_slot_, feedback.target_kbps(), MonotonicNs());
  preview_wanted_.store(feedback.preview(), std::memory_order_relaxed);
  if (!feedback.key_frame_request()) return;
  key_frame_requests_.fetch_add(1, std::memory_order_relaxed);
  key_frame_wanted_.store(true, std::memory_order_release);
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
  const CameraPose pose = pose_.Load();
  const int64_t before_grab_wall_ns = WallNs();
  // A camera whose frames come as JPEG, on a vehicle that sends JPEG: its
  // frame is taken undecoded, and decoded only when it does not fit as it is.
  const bool jpeg_source = passthrough_possible_ && camera_->DeliversJpeg();
  const bool grabbed = jpeg_source ? camera_->GrabJpeg(camera_jpeg_) : camera_->Grab(pose, image_);
  // A device's Grab may wait up to a frame period for the frame: it exists
  // when Grab returns. A rendered frame shows the pose read before Grab.
  const int64_t capture_wall_ns = camera_->RendersAtGrab() ? before_grab_wall_ns : WallNs();
  if (!grabbed && camera_->Ended()) return;  // an end, not a failure: reported next tick
  if (grab_monitor_.OnGrab(grabbed, now_ns) == GrabMonitor::Event::kStalled) {
    log::Warn("camera " + camera_->Describe() + " delivers no frames (" +
              std::to_string(grab_monitor_.failures_in_a_row()) +
              " grabs in a row failed); the vehicle runs on without video (reported once; "
              "counted in the stop summary)");
  }
  grabs_failed_.store(grab_monitor_.failures(), std::memory_order_relaxed);
  camera_stalls_.store(grab_monitor_.stalls(), std::memory_order_relaxed);
  if (!grabbed) return;
  // A tile's preview: at most its rate, the first at once. Paced by the
  // clock, not by counting grabs: after a stall the camera's thread catches
  // up (up to 10 ticks back to back), and one grab in three then sent 13
  // previews in a second on a loaded host. The due time keeps its phase
  // through a tick's jitter, and starts again from now after a stall.
  const bool preview = preview_wanted_.load(std::memory_order_relaxed);
  if (preview) {
    if (!previewing_) next_preview_ns_ = now_ns;
    if (now_ns < next_preview_ns_) return;
    const auto period_ns = static_cast<int64_t>(std::llround(1e9 / preview_config_.rate_hz));
    next_preview_ns_ += period_ns;
    if (next_preview_ns_ <= now_ns) next_preview_ns_ = now_ns + period_ns;
  }
  VideoEncoder& encoder = EncoderFor(preview);
  if (preview != previewing_) {
    // The other stream's references are not this one's: a key frame first.
    previewing_ = preview;
    encoder.RequestKeyFrame();
  }
  // The operator's estimate of the link, followed by the encoder.
  const uint32_t target = share_ != nullptr ? share_->TargetFor(share_slot_, now_ns)
                                            : target_kbps_.load(std::memory_order_relaxed);
  if (target != followed_kbps_) {
    followed_kbps_ = target;
    encoder_->FollowBitrate(target);
    if (preview_encoder_) preview_encoder_->FollowBitrate(target);
  }
  const bool pass_through =
      jpeg_source && !preview &&
      JpegPassesThrough(camera_jpeg_.data(), camera_jpeg_.size(), config_, target);
  if (jpeg_source && !pass_through &&
      !DecodeCameraJpeg(camera_jpeg_, config_, camera_decoded_, image_)) {
    frames_failed_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (!pass_through) {
    if (encoder.SkipFrame()) {
      frames_skipped_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    if (key_frame_wanted_.exchange(false, std::memory_order_acq_rel)) encoder.RequestKeyFrame();
    if (preview) {
      cv::resize(image_, preview_image_, cv::Size(preview_config_.width, preview_config_.height), 0,
                 0, cv::INTER_AREA);
    }
    if (!encoder.Encode(preview ? preview_image_ : image_, encoded_)) {
      frames_failed_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
  }
  const std::vector<uint8_t>& bytes = pass_through ? camera_jpeg_ : encoded_;
  msg::VideoFrame& f = frame_msg_;
  f.seq(++frame_seq_);
  f.capture_wall_ns(capture_wall_ns);
  const CameraConfig& sent = preview ? preview_config_ : config_;
  f.width(static_cast<uint16_t>(sent.width));
  f.height(static_cast<uint16_t>(sent.height));
  f.encoding(codec_name_);
  f.key_frame(pass_through || encoder.last_was_key_frame());
  f.data().assign(bytes.begin(), bytes.end());
  f.pan(static_cast<float>(pose.pan));
  f.tilt(static_cast<float>(pose.tilt));
  f.zoom(static_cast<float>(pose.zoom));
  f.fov_deg(static_cast<float>(ZoomedFovDeg(config_.fov_deg, pose.zoom)));
  f.command_seq(pose.command_seq);
  if (share_ != nullptr) share_->OnSent(share_slot_, bytes.size(), now_ns);
  if (pass_through) frames_passed_through_.fetch_add(1, std::memory_order_relaxed);
  writer_.Write(f);
  frames_.fetch_add(1, std::memory_order_relaxed);
  if (preview) preview_frames_.fetch_add(1, std::memory_order_relaxed);
  if (f.key_frame()) key_frames_sent_.fetch_add(1, std::memory_order_relaxed);
}

VideoEncoder& CameraStreamer::EncoderFor(bool preview) {
  if (!preview) return *encoder_;
  if (!preview_encoder_) {
    preview_encoder_ = MakeVideoEncoder(preview_config_);
    if (followed_kbps_ > 0) preview_encoder_->FollowBitrate(followed_kbps_);
  }
  return *preview_encoder_;
}

CameraCounters CameraStreamer::Counters() const {
  CameraCounters c;
  c.frames_published = frames_.load();
  c.frames_failed = frames_failed_.load();
  c.grabs_failed = grabs_failed_.load();
  c.camera_stalls = camera_stalls_.load();
  c.camera_ended = camera_ended_.load();
  c.key_frame_requests = key_frame_requests_.load();
  c.key_frames_sent = key_frames_sent_.load();
  c.frames_skipped = frames_skipped_.load();
  c.frames_passed_through = frames_passed_through_.load();
  c.target_kbps = target_kbps_.load();
  c.feedback_refused = feedback_refused_.load();
  c.preview = preview_wanted_.load();
  c.preview_frames = preview_frames_.load();
  return c;
}

}  // namespace haptel::video
