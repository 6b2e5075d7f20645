#pragma once
/// @file A vehicle's camera on the link: grabs frames from its source at
/// `camera.rate_hz` on a thread of its own, encodes them (`camera.codec`:
/// JPEG or H.264) and publishes them on haptel/<vehicle>/video — so a slow or
/// stalled camera never delays a control loop or its watchdog. It listens on
/// haptel/<vehicle>/video_feedback for the operator's key frame requests (an
/// H.264 frame was lost: the next frame is an IDR) and the target bitrate,
/// from the participant whose command writer owns the vehicle only
/// (CommandOwner; FeedbackFromOwner): anybody else on the domain could
/// otherwise hold its video at the lowest rung or make it send key frames
/// without end. Any vehicle node has one.
///
/// While the operator shows this vehicle only as a fleet's tile (the
/// feedback's `preview`), it sends a preview: half the width and height
/// (cv::resize, encoded by an encoder of that size) at most kPreviewRate_hz
/// — a tile needs far fewer pixels and frames than the driven screen, and
/// the operator's host decodes them for three vehicles on two cores. Asked
/// for the full picture again, the next frame is a full-size key frame.
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "haptel/config/vehicle.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/codec.hpp"

namespace haptel::video {

struct CameraCounters {
  uint64_t frames_published = 0;
  uint64_t frames_failed = 0;  ///< grabbed but not encoded
  uint64_t grabs_failed = 0;   ///< the camera source delivered no frame
  uint64_t camera_stalls = 0;  ///< stretches of failed grabs long enough to count (GrabMonitor)
  bool camera_ended = false;   ///< a file source that does not loop has ended
  uint64_t key_frame_requests = 0;  ///< the operator's requests received
  uint64_t key_frames_sent = 0;     ///< frames published that decode alone (every JPEG)
  uint64_t frames_skipped = 0;      ///< grabbed but skipped to fit the link (JPEG's lowest rungs)
  uint32_t target_kbps = 0;         ///< the operator's last estimate of the link (0: none came)
  bool preview = false;             ///< sending the preview (the operator shows a tile)
  uint64_t preview_frames = 0;      ///< frames published as previews
  /// Feedback (key frame requests, targets) from another participant than
  /// the vehicle's owner's: ignored.
  uint64_t feedback_refused = 0;
  /// A camera's own JPEGs sent as they came, neither decoded nor encoded
  /// again (a ROS 2 robot's, at the configured size, within the bitrate).
  uint64_t frames_passed_through = 0;
};

/// Whether video feedback written by `sender` is to be followed while the
/// vehicle obeys the command writer `owner`: while one owns it, only
/// feedback from the owner's participant (the same GUID prefix: a run's
/// command and feedback writers share one participant), whatever session
/// the feedback names; while nobody does (empty: nothing to protect, and a
/// vehicle only watched still follows its link), anybody's.
inline bool FeedbackFromOwner(const link::WriterId& owner, const link::WriterId& sender) {
  return owner.empty() || owner.SameParticipant(sender);
}

/// The link's capacity shared among one vehicle's cameras by priority
/// (issue 38: the driven camera first), as WebRTC's BitrateAllocator
/// shares one transport's estimate among its streams.
///
/// The capacity is the link's, not one stream's: each camera's receiver
/// estimates only what reaches it (video::RateEstimator: on overuse 85 % of
/// its own stream's arrivals, otherwise at most 1.5 times them), so on a
/// link the streams share the sum of their receivers' fresh estimates is
/// what the link carries (and what it could carry more). Following its own
/// receiver alone, the first camera never got more than its own share (at
/// 800 kbit/s the pilot's 266 kbit/s against the surveillance camera's
/// 331). Two receivers on one host measure one link; on two hosts, the
/// vehicle's uplink is what they share.
///
/// The split (Split), in priority order (the lowest number first; equal
/// numbers in the order added): each camera is given what is left less a
/// floor (kFloor_kbps) for each camera after it, at most its most (an
/// H.264 encoder's configured bitrate; JPEG's ladder has none). What it
/// takes of the link is what it was given or, when it sends less (a JPEG
/// camera on its top rung), kHeadroom times what it sent over the last
/// second: the rest goes to the cameras after it, so the link is used. What
/// the cameras take never adds up to more than the capacity; when it cannot
/// hold every floor, they share it equally. A camera whose receiver sent no
/// estimate for kFresh_ns (nobody watches it: its frames cross no link) is
/// given 0 (its own setting) and no share. Thread-safe (atomics): each
/// camera's thread and feedback thread call it; allocation-free.
class LinkShare {
 public:
  static constexpr uint32_t kFloor_kbps = 150;
  /// An estimate older than this is no receiver's any more.
  static constexpr int64_t kFresh_ns = 3'000'000'000;
  /// A camera sending less than given takes this many times what it sends.
  static constexpr double kHeadroom = 1.25;

  /// One camera in the split, in priority order.
  struct Demand {
    uint32_t most_kbps = 0;  ///< what its encoder can use at most (0: no bound)
    uint32_t sent_kbps = 0;  ///< what it sent over the last second (0: unknown)
  };
  /// Splits `capacity_kbps` among `count` cameras listed in priority order
  /// (first first) into `targets_kbps` (kbit/s each): see the class comment.
  static void Split(uint32_t capacity_kbps, const Demand* demands, int count,
                    uint32_t* targets_kbps);

  /// A camera of `priority` (0 first) whose encoder uses at most
  /// `most_kbps` (0: no bound); returns its slot. Call for each before the
  /// cameras start.
  int Add(int priority, uint32_t most_kbps = 0);
  /// Camera `slot`'s receiver estimated the link at `kbps` (0: none).
  void OnEstimate(int slot, uint32_t kbps, int64_t now_ns);
  /// Camera `slot` sent `bytes` at `now_ns`.
  void OnSent(int slot, size_t bytes, int64_t now_ns);
  /// What camera `slot`'s encoder is to follow now (0: its own setting,
  /// no fresh estimate from its receiver).
  uint32_t TargetFor(int slot, int64_t now_ns) const;
  /// The link's capacity now: the sum of the fresh estimates (0: none).
  uint32_t CapacityKbps(int64_t now_ns) const;
  /// Camera `slot`'s sent rate over the last second, kbit/s.
  uint32_t SentKbps(int slot, int64_t now_ns) const;

 private:
  static constexpr int kMaxSlots = kMaxVehicleCameras;
  struct Slot {
    int priority = 0;
    uint32_t most_kbps = 0;
    std::atomic<uint32_t> estimate_kbps{0};
    std::atomic<int64_t> estimate_ns{0};
    // Bytes sent in the current and the previous second.
    std::atomic<int64_t> window_start_ns{0};
    std::atomic<uint64_t> bytes_now{0};
    std::atomic<uint64_t> bytes_before{0};
  };
  bool Fresh(const Slot& s, int64_t now_ns) const {
    return s.estimate_kbps.load(std::memory_order_relaxed) > 0 &&
           now_ns - s.estimate_ns.load(std::memory_order_relaxed) < kFresh_ns;
  }
  std::array<Slot, kMaxSlots> slots_;
  std::array<int, kMaxSlots> order_{};  ///< slots by priority (set by Add)
  int count_ = 0;
};

class CameraStreamer {
 public:
  /// A preview's most frames per second.
  static constexpr double kPreviewRate_hz = 10.0;

  /// The command writer the vehicle obeys now (empty: none), from any thread.
  using OwnerWriter = std::function<link::WriterId()>;

  /// `camera` must not be null; `participant` must outlive the streamer.
  /// `owner_writer` says whose feedback is taken (FeedbackFromOwner): the
  /// vehicle's owner for the driven camera, the camera's holder for any
  /// other. It must not be null. `driven`: the vehicle's driven camera, on
  /// haptel/<vehicle>/video; else on haptel/<vehicle>/video/<camera name>
  /// (link::VideoTopic), each with its feedback topic. `share` (optional,
  /// must outlive the streamer) shares the link's capacity among the
  /// vehicle's cameras by priority (LinkShare).
  CameraStreamer(const CameraConfig& config, std::unique_ptr<CameraSource> camera,
                 link::Participant& participant, const std::string& vehicle_name,
                 OwnerWriter owner_writer, bool driven = true, LinkShare* share = nullptr);
  ~CameraStreamer();
  CameraStreamer(const CameraStreamer&) = delete;
  CameraStreamer& operator=(const CameraStreamer&) = delete;

  void Start();
  void Stop();
  /// Where the camera is now (any thread; a synthetic source renders from it).
  void SetPose(const CameraPose& pose) { pose_.Store(pose); }
  CameraCounters Counters() const;
  /// Feedback refused (CameraCounters::feedback_refused), cheaper than Counters().
  uint64_t feedback_refused() const { return feedback_refused_.load(std::memory_order_relaxed); }

 private:
  void Tick(int64_t now_ns);
  /// The encoder for this frame (the full one, or the preview's, made on
  /// first use), its image, and whether this grab is sent at all.
  VideoEncoder& EncoderFor(bool preview);
  void OnFeedback(const msg::VideoFeedback& feedback, const link::WriterId& sender);

  const CameraConfig config_;
  const OwnerWriter owner_writer_;
  const bool
      passthrough_possible_;  ///< the vehicle sends JPEG: a camera's own JPEG may go as it is
  std::unique_ptr<CameraSource> camera_;
  Seqlock<CameraPose> pose_;
  GrabMonitor grab_monitor_;
  bool end_reported_ = false;
  std::unique_ptr<VideoEncoder> encoder_;
  const CameraConfig preview_config_;  ///< half the size, kPreviewRate_hz
  std::unique_ptr<VideoEncoder> preview_encoder_;
  cv::Mat preview_image_;
  bool previewing_ = false;      ///< camera thread only: the last frame sent was a preview
  int64_t next_preview_ns_ = 0;  ///< camera thread only: when a preview is next due
  const char* codec_name_;
  cv::Mat image_;
  msg::VideoFrame frame_msg_;
  std::vector<uint8_t> encoded_;
  std::vector<uint8_t> camera_jpeg_;  ///< a JPEG source's frame, undecoded
  cv::Mat camera_decoded_;            ///< its picture when it must be encoded again
  uint64_t frame_seq_ = 0;
  std::atomic<uint64_t> frames_{0}, frames_failed_{0}, grabs_failed_{0}, camera_stalls_{0};
  std::atomic<uint64_t> key_frame_requests_{0}, key_frames_sent_{0}, frames_skipped_{0},
      frames_passed_through_{0};
  /// The operator's estimate of the link (kbit/s; 0: none yet), set by the
  /// feedback's DDS thread; the camera's thread hands it to the encoder.
  std::atomic<uint32_t> target_kbps_{0};
  uint32_t followed_kbps_ = 0;  ///< camera thread only
  /// Set by the feedback's DDS thread, taken by the camera's thread.
  std::atomic<bool> key_frame_wanted_{false};
  /// The operator shows only a tile (set by the feedback's DDS thread).
  std::atomic<bool> preview_wanted_{false};
  std::atomic<uint64_t> preview_frames_{0};
  std::atomic<uint64_t> feedback_refused_{0};
  std::atomic<bool> camera_ended_{false};
  LinkShare* share_ = nullptr;
  int share_slot_ = -1;
  link::VideoWriter writer_;
  std::unique_ptr<PeriodicThread> loop_;
  std::unique_ptr<link::VideoFeedbackReader> feedback_;  // last: destroyed first
};

}  // namespace haptel::video
