#pragma once
/// @file The rate the link can carry, estimated on the operator's side from
/// each video frame's arrival, after Google Congestion Control
/// (draft-ietf-rmcat-gcc-02) as WebRTC builds it today: a delay-based
/// estimate (the trend of one-way delay variation, an adaptive threshold, an
/// AIMD rate controller) and a loss-based one, the smaller of the two being
/// the target bitrate the vehicle's encoder is asked to follow.
///
/// Why from delay: a link's queue fills before it drops. When the video
/// sends faster than the link carries, each frame arrives a little later
/// relative to its capture than the one before; the trend of that growth
/// (ms of delay per ms of time) crosses a threshold well before packets are
/// lost, and the rate is cut to 85 % of what is arriving. The threshold
/// adapts to the delay's own noise (jitter), so a jittery but uncongested
/// link is not mistaken for a congested one, and it grows quickly with
/// large variations so a competing flow does not starve the video.
///
/// What the delay is measured between: when each frame was sent (the
/// sender's stamp at the moment it hands the encoded frame to the link —
/// DDS's source timestamp, link::SampleStamps — not its capture, which
/// comes before the camera's rendering and the encoder's work) and when it
/// arrived (stamped on the receiving transport's thread, before the frame
/// is queued for decoding). So the CPU either host spends making or
/// showing pictures is not in it, only the way between: time spent
/// decoding and drawing three fleets' streams on two cores is no queue.
/// Only differences of send stamps and of arrival stamps are used (the
/// inter-group delay variation of WebRTC's InterArrivalDelta and
/// TrendlineEstimator): the vehicle's and the operator's clocks need not
/// agree. A group is what was sent within kGroupSpan_s of its first frame
/// (a frame is sent as one burst, and arrives when its last packet does);
/// a frame that arrives within kBurstDelta_s of the group's last, sooner
/// after it than it was sent after it, joins the group too: the receiving
/// host held the packets back (its receive thread was not scheduled) and
/// delivered them together, and that says nothing of the network (WebRTC's
/// burst grouping, at most kMaxBurst_s long). Losses are gaps in the frame
/// numbers.
///
/// What arrives bounds the estimate, as GCC's acknowledged bitrate does
/// (WebRTC's loss-based estimator cuts to a share of it): a link whose
/// drop-tail queue is short fills and drops before the delay trend can
/// rise (a 25 kB JPEG frame is one burst of 200 ms at 1 Mbit/s), so the
/// trend stays flat while frames are lost; the cut for loss then goes no
/// higher than the rate received, and neither estimate grows past 1.5
/// times it (a sender that does not use its rate — the JPEG ladder on a
/// rung below the target — earns no unbounded one, which would later let
/// it climb a rung the link cannot carry). And a link that carries no
/// whole frame at all (every burst cut) says so only by its silence:
/// OnSilence halves the target while frames are expected and none come.
/// A silence after which the frame numbers run on (no frame was lost in
/// it) was the sender's — its camera or its host stalled, as a loaded
/// vehicle's does — not the link's: its cuts are undone when it ends.
///
/// Not thread-safe; the operator's video thread owns it. Allocation-free
/// after construction.
#include <array>
#include <cstddef>
#include <cstdint>

namespace haptel::video {

struct RateEstimatorConfig {
  double min_kbps = 100.0;     ///< never asks for less
  double max_kbps = 6000.0;    ///< nor more (what the encoder can use)
  double start_kbps = 1000.0;  ///< before anything is known
  /// At most one target sent to the vehicle per this period (s): 10 Hz.
  double feedback_period_s = 0.1;

  /// Throws std::invalid_argument naming the field unless
  /// 0 < min_kbps <= start_kbps <= max_kbps and 0 < feedback_period_s.
  void ValidateOrThrow() const;
};

/// What the delay trend says about the link's queue.
enum class LinkUsage { kNormal, kOveruse, kUnderuse };

class RateEstimator {
 public:
  explicit RateEstimator(const RateEstimatorConfig& config = {});

  /// One frame received whole: `frame_number` the sender's count (a gap is
  /// a loss), `sent_s` when the sender handed it to the link on its clock,
  /// `arrival_s` when it arrived on this side's clock, `bytes` its encoded
  /// size. Frames arriving out of order (a number below the newest) are
  /// counted as received but not used for the delay trend.
  void OnFrame(uint64_t frame_number, double sent_s, double arrival_s, size_t bytes);

  /// Called now and then (a few times a second or more) while a sender is
  /// known to publish frames: when none has arrived for kSilence_s (since
  /// the last frame, or since the first call), the loss-based estimate
  /// halves, once per kSilence_s, and a target is due at once. Frames that
  /// never arrive whole (a burst longer than the link's queue) are losses
  /// no gap can show. Returns whether it cut now (send the target).
  bool OnSilence(double now_s);

  /// The bitrate to ask of the encoder now (kbps): the smaller of the
  /// delay-based and the loss-based estimates, within [min, max].
  double target_kbps() const;
  LinkUsage usage() const { return usage_; }
  /// What arrived over the last kRateWindow_s (kbps); 0 before any frame.
  double received_kbps() const { return received_kbps_; }
  /// The share of frames lost over the last loss window (0..1).
  double loss_share() const { return loss_share_; }
  /// The delay trend as compared with the threshold, and the threshold (ms).
  double trend_ms() const { return modified_trend_; }
  double threshold_ms() const { return threshold_ms_; }
  /// How many times the delay-based estimate was cut (overuse).
  uint64_t decreases() const { return decreases_; }

  /// Whether a target is due to be sent at `now_s` (at most once per
  /// feedback period, and at once after a cut); marks it sent.
  bool FeedbackDue(double now_s);

  /// The window the received rate is measured over (s).
  static constexpr double kRateWindow_s = 0.5;
  /// No frame for this long while frames are expected: the link carries none.
  static constexpr double kSilence_s = 0.5;
  /// Frames sent within this of a group's first are one group (WebRTC: 5 ms).
  static constexpr double kGroupSpan_s = 0.005;
  /// A frame arriving within this of the group's last, sooner than it was
  /// sent after it, was held back on the receiving host: the same group.
  static constexpr double kBurstDelta_s = 0.005;
  /// A group held together so is at most this long (WebRTC: 100 ms).
  static constexpr double kMaxBurst_s = 0.1;

 private:
  /// Whether a frame sent at `sent_s` and arrived at `arrival_s` joins the group.
  bool BelongsToGroup(double sent_s, double arrival_s) const;
  void UpdateTrend(double arrival_delta_ms, double send_delta_ms, double arrival_ms);
  void Detect(double send_delta_ms, double arrival_ms);
  void UpdateThreshold(double arrival_ms);
  void UpdateRate(double now_s);
  void UpdateLoss(uint64_t frame_number, double now_s);

  RateEstimatorConfig config_;

  // The group being gathered, and the complete one before it.
  struct Group {
    double first_sent_s = 0, last_sent_s = 0;
    double first_arrival_s = 0, last_arrival_s = 0;
  };
  bool have_group_ = false, have_previous_ = false;
  uint64_t newest_frame_ = 0;
  Group group_, previous_;

  // The trendline: accumulated and smoothed delay variation against arrival
  // time, over the last kWindow groups (a ring).
  static constexpr int kWindow = 20;
  double first_arrival_ms_ = -1;
  double accumulated_ms_ = 0, smoothed_ms_ = 0;
  std::array<double, kWindow> times_ms_{}, delays_ms_{};
  int window_count_ = 0, window_next_ = 0;
  int deltas_ = 0;
  double modified_trend_ = 0, previous_trend_ = 0;
  double threshold_ms_ = 12.5;
  double last_threshold_update_ms_ = -1;
  double time_over_using_ms_ = -1;
  int overuse_count_ = 0;
  LinkUsage usage_ = LinkUsage::kNormal;

  // What arrived: a ring of (arrival, bytes) over the rate window.
  static constexpr int kArrivals = 512;
  std::array<double, kArrivals> arrival_s_{};
  std::array<size_t, kArrivals> arrival_bytes_{};
  int arrivals_head_ = 0, arrivals_count_ = 0;
  size_t window_bytes_ = 0;
  double first_frame_s_ = -1;
  double received_kbps_ = 0;

  // The AIMD rate controller.
  enum class RateState { kHold, kIncrease, kDecrease };
  RateState state_ = RateState::kIncrease;
  double delay_kbps_;
  double last_rate_update_s_ = -1;
  double link_capacity_kbps_ = -1;  ///< the received rate at the last cut (-1: unknown)
  uint64_t decreases_ = 0;
  double last_cut_s_ = -1e300;

  // Loss: frames expected and received since the window began.
  double loss_kbps_;
  double loss_window_start_s_ = -1;
  uint64_t loss_window_first_ = 0;
  uint64_t loss_window_received_ = 0;
  double loss_share_ = 0;

  double last_frame_s_ = -1;  ///< the newest arrival, or the first OnSilence
  double last_silence_cut_s_ = -1;
  double before_silence_kbps_ = 0;  ///< the loss-based estimate before the silence's cuts
  double next_feedback_s_ = 0;
  bool cut_pending_ = false;
};

}  // namespace haptel::video
