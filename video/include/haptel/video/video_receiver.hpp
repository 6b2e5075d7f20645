#pragma once
/// @file Receives the vehicle's video frames and decodes them off the DDS thread.
///
/// The DDS callback only moves the bytes into a queue; a decoder thread turns
/// them into the screen image and measures latency from the capture stamp
/// (CLOCK_REALTIME of the vehicle's host: meaningful when both run on one
/// host or on hosts whose clocks are synchronised). JPEG frames each decode
/// alone, so the latest wins and older ones waiting are dropped; H.264 delta
/// frames need every frame before them, so all are decoded in order.
///
/// When an H.264 frame is lost (a gap in the frame numbers) or corrupt, no
/// good picture can come before a key frame: the last picture stays on the
/// screen marked stale (a red frame and "STALE"), the time spent so is
/// measured, and the vehicle is asked for a key frame on
/// haptel/<vehicle>/video_feedback at most every kKeyFrameRequestPeriodNs,
/// again and again until one decodes.
///
/// Every frame's arrival also feeds the link's rate estimate
/// (RateEstimator, after Google Congestion Control; its delay is between
/// DDS's send stamp and the arrival stamped in the DDS callback, before
/// the frame waits for the decoder): at most ten
/// times a second the estimate goes to the vehicle on the same feedback
/// topic, and its encoder follows it (H.264's bitrate, JPEG's ladder).
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "haptel/core/histogram.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/video/frame.hpp"
#include "haptel/video/rate_estimator.hpp"

namespace haptel::video {

struct VideoStats {
  uint64_t frames = 0;           ///< frames received and (when decoding) decoded
  uint64_t dropped = 0;          ///< replaced in the slot before the decoder got to them
  uint64_t decode_failures = 0;  ///< corrupt frames, counted and dropped
  uint64_t frames_lost = 0;      ///< gaps in the vehicle's frame numbers (never received)
  uint64_t frames_skipped =
      0;  ///< H.264 delta frames not decoded (after a gap, or while a key frame is awaited)
  uint64_t key_frame_requests = 0;  ///< asked of the vehicle (a frame lost or corrupt)
  uint64_t key_frames = 0;          ///< received frames that decode alone
  double fps = 0.0;
  double latency_ms_p50 = 0.0;  ///< capture -> decoded
  double latency_ms_p99 = 0.0;
  double kbps = 0.0;         ///< the video's bitrate as received, kbit/s
  uint64_t bytes = 0;        ///< the video's bytes received (every frame's)
  double stale_s = 0.0;      ///< time the screen showed an old picture marked stale
  double target_kbps = 0.0;  ///< the link's rate as last estimated and sent to the vehicle
  uint64_t rate_cuts = 0;    ///< times the estimate was cut for a filling queue (overuse)
  bool tile = false;         ///< shown only as a tile: the vehicle is asked for a preview
};

class VideoReceiver final : public FrameSource {
 public:
  using FrameObserver = std::function<void(const msg::VideoFrame&, const link::SampleStamps&)>;
  /// Key frame requests while one is awaited: at most one per this period.
  static constexpr int64_t kKeyFrameRequestPeriodNs = 100'000'000;

  /// Subscribes to haptel/<vehicle>/video on `participant` and publishes
  /// key frame requests on haptel/<vehicle>/video_feedback, as `session`
  /// (the run's, as its commands: the vehicle takes its owner's feedback
  /// only). With `decode` false frames are only counted (no screen to show
  /// them on; no requests).
  /// `camera`: another camera than the driven one (its name: the stream on
  /// haptel/<vehicle>/video/<camera>, feedback on video_feedback/<camera>).
  /// `on_frame` (may be empty) hears every frame as it arrives (on the DDS
  /// thread, before it waits for the decoder; short, no blocking): a camera
  /// station's command-to-picture latency from the frame's command_seq.
  VideoReceiver(link::Participant& participant, const std::string& vehicle, uint64_t session,
                bool decode, const std::string& camera = {}, FrameObserver on_frame = {});
  /// A receiver on no link: it receives nothing (zero frames), and runs
  /// no thread (a simulated-time run, whose driver reads the state).
  VideoReceiver();
  ~VideoReceiver() override;

  VideoStats Stats() const;
  /// Whether this vehicle's video is shown only as a fleet's tile (true) or
  /// on the driven screen (false, the start): the vehicle is told at once
  /// and with every rate estimate after (VideoFeedback's `preview`), and
  /// sends a small, slow preview while it is a tile (CameraStreamer). Any
  /// thread; on no link, nothing.
  void ShowAsTile(bool tile);
  /// The latest decoded image without copying it: a short lock, any thread.
  Frame Latest() const override;
  /// The latest good picture as JPEG; empty before the first. JPEG frames
  /// are kept as they came; an H.264 picture is encoded when asked (without
  /// a screen: the latest key frame, decoded then). Any thread, now and then
  /// (a console's thumbnail).
  std::vector<uint8_t> LatestPicture() const;

 private:
  struct Pending {
    std::vector<uint8_t> bytes;
    int64_t capture_ns = 0;
    uint64_t seq = 0;
    uint64_t command_seq = 0;
    float zoom = 1.0F;
    bool key_frame = false;
    bool h264 = false;
  };

  void OnFrame(const msg::VideoFrame& frame, const link::SampleStamps& stamps);
  void DecodeLoop();
  /// Decodes one frame in order; returns whether it gave a picture.
  bool DecodeOne(Pending& frame, cv::Mat& image);
  void RequestKeyFrameIfDue(int64_t now_ns);
  /// The estimator's silence check (RateEstimator::OnSilence) while the
  /// vehicle publishes video; sends the cut target.
  void CheckSilence(int64_t now_ns);
  /// The target as a feedback sample, stamped `now_ns` (under mutex_).
  msg::VideoFeedback RateFeedback(int64_t now_ns, uint64_t last_frame_seq);

  bool decode_;
  uint64_t session_ = 0;  ///< carried by every feedback sample
  FrameObserver on_frame_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Pending> pending_;
  std::vector<std::vector<uint8_t>> spare_;  ///< byte buffers going round: no allocation per frame
  bool stop_ = false;
  Frame latest_;
  std::shared_ptr<const cv::Mat> latest_good_;  ///< the last good picture, unmarked
  std::vector<uint8_t> last_bytes_;             ///< the latest good JPEG frame's bytes
  std::vector<uint8_t> last_key_bytes_;         ///< without a screen: the latest H.264 key frame
  std::unique_ptr<VideoDecoder> decoder_;       ///< made for the codec the frames carry
  Histogram latency_{100.0, 5000};              // µs bins up to 500 ms
  uint64_t frames_ = 0;
  uint64_t dropped_ = 0;
  uint64_t decode_failures_ = 0;
  uint64_t frames_lost_ = 0;
  uint64_t frames_skipped_ = 0;
  uint64_t key_frame_requests_ = 0;
  uint64_t key_frames_ = 0;
  uint64_t last_seq_ = 0;     ///< the last frame number received (0: none yet)
  uint64_t bytes_ = 0;        ///< received after the first frame (the bitrate's numerator)
  uint64_t total_bytes_ = 0;  ///< every frame's
  int64_t first_arrival_ns_ = 0;
  int64_t last_arrival_ns_ = 0;
  int64_t stale_since_ns_ = 0;  ///< 0: not stale
  int64_t stale_ns_ = 0;        ///< stretches of staleness that ended
  int64_t last_request_ns_ = 0;
  uint64_t feedback_seq_ = 0;
  RateEstimator estimator_{RateEstimatorFor()};
  double target_kbps_sent_ = 0.0;
  bool tile_ = false;  ///< shown only as a tile: ask for the preview (under mutex_)
  static RateEstimatorConfig RateEstimatorFor() {
    RateEstimatorConfig c;
    // Start at the most and cut on the first sign of a filling queue: a
    // link that carries the vehicle's file's video never changes it (the
    // vehicle caps the target at its file's bitrate or quality; JPEG at
    // quality 80 is about 6 Mbit/s), and a slow one is found within a second.
    c.max_kbps = 20000.0;
    c.start_kbps = c.max_kbps;
    return c;
  }
  int64_t first_frame_ns_ = 0;
  int64_t last_frame_ns_ = 0;
  std::thread decoder_thread_;
  std::unique_ptr<link::VideoFeedbackWriter> feedback_;  ///< null on no link
  bool reader_ready_ = false;  ///< reader_ made and not yet being destroyed (under mutex_)
  std::unique_ptr<link::VideoReader> reader_;  // last: destroyed first
};

/// `picture` with a visible stale mark: a red frame round it and "STALE".
cv::Mat MarkStale(const cv::Mat& picture);

}  // namespace haptel::video
