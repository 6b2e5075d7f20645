#include "haptel/video/rate_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace haptel::video {

namespace {

// The delay trend (draft-ietf-rmcat-gcc-02 §5.3-5.4, WebRTC's trendline).
constexpr double kSmoothing = 0.9;        ///< of the accumulated delay
constexpr double kTrendGain = 4.0;        ///< the slope's gain against the threshold
constexpr int kMaxDeltas = 60;            ///< the slope is scaled by at most this many deltas
constexpr double kOveruseTime_ms = 10.0;  ///< over the threshold this long: overuse
// The adaptive threshold (§5.4): up fast, down slowly, within [6, 600] ms.
constexpr double kThresholdUp = 0.0087;
constexpr double kThresholdDown = 0.039;
constexpr double kThresholdMin_ms = 6.0, kThresholdMax_ms = 600.0;
// The rate controller (§5.5).
constexpr double kBeta = 0.85;  ///< a cut takes the rate to this share of what arrives
constexpr double kMultiplicativeGain = 1.08;  ///< per second, far from the link's capacity
constexpr double kPacketBits = 1200.0 * 8.0;  ///< the additive step: a packet per response time
constexpr double kResponseTime_s = 0.2;       ///< the link's round trip (small) plus 100 ms
constexpr double kMinCutInterval_s = 0.3;     ///< one cut per queue drain
// Loss (§6): cut above 10 %, grow below 2 %, over windows of a second.
constexpr double kLossWindow_s = 1.0;
constexpr double kLossHigh = 0.10, kLossLow = 0.02;
constexpr double kSilenceRepeat_s = 1.0;  ///< halvings for silence at most this often

}  // namespace

void RateEstimatorConfig::ValidateOrThrow() const {
  const auto fail = [](const std::string& field, const std::string& expected) {
    throw std::invalid_argument("rate estimator: " + field + ": expected " + expected);
  };
  if (!(min_kbps > 0)) fail("min_kbps", "a rate above 0");
  if (!(start_kbps >= min_kbps)) fail("start_kbps", "at least min_kbps");
  if (!(max_kbps >= start_kbps) || !std::isfinite(max_kbps))
    fail("max_kbps", "a finite rate, at least start_kbps");
  if (!(feedback_period_s > 0)) fail("feedback_period_s", "a period above 0 s");
}

RateEstimator::RateEstimator(const RateEstimatorConfig& config)
    : config_(config), delay_kbps_(config.start_kbps), loss_kbps_(config.max_kbps) {
  config_.ValidateOrThrow();
}

double RateEstimator::target_kbps() const {
  return std::clamp(std::min(delay_kbps_, loss_kbps_), config_.min_kbps, config_.max_kbps);
}

bool RateEstimator::FeedbackDue(double now_s) {
  if (now_s < next_feedback_s_) return false;
  next_feedback_s_ = now_s + config_.feedback_period_s;
  cut_pending_ = false;
  return true;
}

bool RateEstimator::OnSilence(double now_s) {
  if (last_frame_s_ < 0) last_frame_s_ = now_s;
  if (now_s - last_frame_s_ < kSilence_s) return false;
  // Again only once the sender had time to follow the last cut (its
  // encoder steps down over several frames).
  if (last_silence_cut_s_ >= 0 && now_s - last_silence_cut_s_ < kSilenceRepeat_s) return false;
  if (last_silence_cut_s_ < 0) before_silence_kbps_ = loss_kbps_;  // a silence begins
  last_silence_cut_s_ = now_s;
  loss_kbps_ = std::clamp(0.5 * target_kbps(), config_.min_kbps, config_.max_kbps);
  received_kbps_ = 0;  // nothing arrives
  cut_pending_ = true;
  next_feedback_s_ = std::min(next_feedback_s_, now_s);
  return true;
}

void RateEstimator::OnFrame(uint64_t frame_number, double sent_s, double arrival_s, size_t bytes) {
  last_frame_s_ = std::max(last_frame_s_, arrival_s);
  if (last_silence_cut_s_ >= 0) {
    // The silence is over. When the frame numbers run on (none was lost
    // in it), the sender sent nothing — its camera or its host stalled —
    // which says nothing of the link: its cuts are undone, at once. Else
    // the frames lost in the silence were answered by its cuts: the loss
    // window starts again here, not counting them twice.
    // (Before any frame, only a first frame numbered 1 shows that.)
    if (have_group_ ? frame_number == newest_frame_ + 1 : frame_number == 1) {
      loss_kbps_ = before_silence_kbps_;
      cut_pending_ = true;
      next_feedback_s_ = std::min(next_feedback_s_, arrival_s);
    }
    last_silence_cut_s_ = -1;
    loss_window_start_s_ = -1;
  }
  // What arrived over the rate window.
  const int slot = (arrivals_head_ + arrivals_count_) % kArrivals;
  if (arrivals_count_ == kArrivals) {  // full: the oldest goes
    window_bytes_ -= arrival_bytes_[static_cast<size_t>(arrivals_head_)];
    arrivals_head_ = (arrivals_head_ + 1) % kArrivals;
    --arrivals_count_;
  }
  arrival_s_[static_cast<size_t>(slot)] = arrival_s;
  arrival_bytes_[static_cast<size_t>(slot)] = bytes;
  ++arrivals_count_;
  window_bytes_ += bytes;
  while (arrivals_count_ > 1 &&
         arrival_s_[static_cast<size_t>(arrivals_head_)] < arrival_s - kRateWindow_s) {
    window_bytes_ -= arrival_bytes_[static_cast<size_t>(arrivals_head_)];
    arrivals_head_ = (arrivals_head_ + 1) % kArrivals;
    --arrivals_count_;
  }
  // Over the whole window once there has been one (a shorter start is
  // measured over what it had, at least 0.1 s).
  if (first_frame_s_ < 0) first_frame_s_ = arrival_s;
  const double span_s = std::clamp(arrival_s - first_frame_s_, 0.1, kRateWindow_s);
  received_kbps_ = static_cast<double>(window_bytes_) * 8.0 / 1000.0 / span_s;

  UpdateLoss(frame_number, arrival_s);

  // A sender that started over (a new vehicle process) starts the trend over.
  if (have_group_ && frame_number + 1000 < newest_frame_) have_group_ = have_previous_ = false;
  if (!have_group_) {
    have_group_ = true;
    newest_frame_ = frame_number;
    group_ = {sent_s, sent_s, arrival_s, arrival_s};
    if (last_rate_update_s_ < 0) last_rate_update_s_ = arrival_s;
    return;
  }
  if (frame_number <= newest_frame_) return;  // late or repeated: no place in the trend
  newest_frame_ = frame_number;
  if (BelongsToGroup(sent_s, arrival_s)) {
    group_.last_sent_s = std::max(group_.last_sent_s, sent_s);
    group_.last_arrival_s = arrival_s;
    return;
  }
  // The group is complete: its delay variation against the one before.
  if (have_previous_) {
    const double send_delta_ms = (group_.last_sent_s - previous_.last_sent_s) * 1e3;
    const double arrival_delta_ms = (group_.last_arrival_s - previous_.last_arrival_s) * 1e3;
    UpdateTrend(arrival_delta_ms, send_delta_ms, group_.last_arrival_s * 1e3);
    UpdateRate(arrival_s);
  }
  previous_ = group_;
  have_previous_ = true;
  group_ = {sent_s, sent_s, arrival_s, arrival_s};
}

bool RateEstimator::BelongsToGroup(double sent_s, double arrival_s) const {
  // Sent within a burst of the group's first: one group (a frame's
  // packets, or frames sent back to back).
  if (sent_s - group_.first_sent_s <= kGroupSpan_s) return true;
  // Arrived right after the group, sooner than it was sent after it, and
  // the group not yet long: the receiving host held the packets back and
  // delivered them together (its receive thread was not scheduled). What
  // the network did cannot be told from that: WebRTC's burst grouping.
  const double arrival_delta_s = arrival_s - group_.last_arrival_s;
  const double send_delta_s = sent_s - group_.last_sent_s;
  return arrival_delta_s >= 0 && arrival_delta_s <= kBurstDelta_s &&
         arrival_delta_s - send_delta_s < 0 && arrival_s - group_.first_arrival_s < kMaxBurst_s;
}

void RateEstimator::UpdateTrend(double arrival_delta_ms, double send_delta_ms, double arrival_ms) {
  ++deltas_;
  if (first_arrival_ms_ < 0) first_arrival_ms_ = arrival_ms;
  accumulated_ms_ += arrival_delta_ms - send_delta_ms;
  smoothed_ms_ = kSmoothing * smoothed_ms_ + (1 - kSmoothing) * accumulated_ms_;
  times_ms_[static_cast<size_t>(window_next_)] = arrival_ms - first_arrival_ms_;
  delays_ms_[static_cast<size_t>(window_next_)] = smoothed_ms_;
  window_next_ = (window_next_ + 1) % kWindow;
  window_count_ = std::min(window_count_ + 1, kWindow);
  if (window_count_ == kWindow) {
    // The least-squares slope of smoothed delay against arrival time.
    double mean_t = 0, mean_d = 0;
    for (int i = 0; i < kWindow; ++i) {
      mean_t += times_ms_[static_cast<size_t>(i)];
      mean_d += delays_ms_[static_cast<size_t>(i)];
    }
    mean_t /= kWindow;
    mean_d /= kWindow;
    double num = 0, den = 0;
    for (int i = 0; i < kWindow; ++i) {
      const double dt = times_ms_[static_cast<size_t>(i)] - mean_t;
      num += dt * (delays_ms_[static_cast<size_t>(i)] - mean_d);
      den += dt * dt;
    }
    const double slope = den > 0 ? num / den : 0.0;
    modified_trend_ = std::min(deltas_, kMaxDeltas) * slope * kTrendGain;
  }
  Detect(send_delta_ms, arrival_ms);
}

void RateEstimator::Detect(double send_delta_ms, double arrival_ms) {
  if (deltas_ < 2) return;
  if (modified_trend_ > threshold_ms_) {
    // Over for long enough, twice in a row, and not falling: the queue grows.
    time_over_using_ms_ =
        time_over_using_ms_ < 0 ? send_delta_ms / 2 : time_over_using_ms_ + send_delta_ms;
    ++overuse_count_;
    if (time_over_using_ms_ > kOveruseTime_ms && overuse_count_ > 1 &&
        modified_trend_ >= previous_trend_) {
      time_over_using_ms_ = 0;
      overuse_count_ = 0;
      usage_ = LinkUsage::kOveruse;
    }
  } else if (modified_trend_ < -threshold_ms_) {
    time_over_using_ms_ = -1;
    overuse_count_ = 0;
    usage_ = LinkUsage::kUnderuse;
  } else {
    time_over_using_ms_ = -1;
    overuse_count_ = 0;
    usage_ = LinkUsage::kNormal;
  }
  previous_trend_ = modified_trend_;
  UpdateThreshold(arrival_ms);
}

void RateEstimator::UpdateThreshold(double arrival_ms) {
  if (last_threshold_update_ms_ < 0) last_threshold_update_ms_ = arrival_ms;
  const double magnitude = std::abs(modified_trend_);
  // A spike far over the threshold (a key frame, a route change) is not
  // allowed to drag the threshold up.
  if (magnitude > threshold_ms_ + 15.0) {
    last_threshold_update_ms_ = arrival_ms;
    return;
  }
  const double k = magnitude < threshold_ms_ ? kThresholdDown : kThresholdUp;
  const double dt_ms = std::min(arrival_ms - last_threshold_update_ms_, 100.0);
  threshold_ms_ = std::clamp(threshold_ms_ + k * (magnitude - threshold_ms_) * dt_ms,
                             kThresholdMin_ms, kThresholdMax_ms);
  last_threshold_update_ms_ = arrival_ms;
}

void RateEstimator::UpdateRate(double now_s) {
  const double dt_s = std::clamp(now_s - last_rate_update_s_, 0.0, 1.0);
  last_rate_update_s_ = now_s;
  const double current = delay_kbps_;
  switch (usage_) {
    case LinkUsage::kOveruse: {
      // Once per queue drain: the queue the overuse built keeps the trend
      // up for a while after the cut.
      if (state_ != RateState::kDecrease || now_s - last_cut_s_ >= kMinCutInterval_s) {
        const double cut = kBeta * received_kbps_;
        if (cut < current) {
          delay_kbps_ = cut;
          ++decreases_;
          cut_pending_ = true;
          next_feedback_s_ = std::min(next_feedback_s_, now_s);
        }
        link_capacity_kbps_ = received_kbps_;
        last_cut_s_ = now_s;
      }
      state_ = RateState::kDecrease;
      break;
    }
    case LinkUsage::kUnderuse:
      // The queue drains: hold until it is empty.
      state_ = RateState::kHold;
      break;
    case LinkUsage::kNormal: {
      if (state_ != RateState::kIncrease) {
        state_ = RateState::kIncrease;
        break;  // increase from the next frame on
      }
      // A link that got faster than its last known capacity: back to
      // searching multiplicatively.
      if (link_capacity_kbps_ > 0 && current > 1.5 * link_capacity_kbps_) link_capacity_kbps_ = -1;
      const bool near_capacity = link_capacity_kbps_ > 0;
      double next = near_capacity ? current + kPacketBits / 1000.0 / kResponseTime_s * dt_s
                                  : current * std::pow(kMultiplicativeGain, dt_s);
      // Never far above what arrives: a sender that does not use its rate
      // (a still picture) must not earn an unbounded one.
      next = std::min(next, std::max(current, 1.5 * received_kbps_ + 10.0));
      delay_kbps_ = next;
      break;
    }
  }
  delay_kbps_ = std::clamp(delay_kbps_, config_.min_kbps, config_.max_kbps);
}

void RateEstimator::UpdateLoss(uint64_t frame_number, double now_s) {
  if (loss_window_start_s_ < 0 || frame_number + 1000 < loss_window_first_) {
    loss_window_start_s_ = now_s;
    loss_window_first_ = frame_number;
    loss_window_received_ = 0;
  }
  ++loss_window_received_;
  if (now_s - loss_window_start_s_ < kLossWindow_s) return;
  const uint64_t newest = std::max(frame_number, newest_frame_);
  const double expected = static_cast<double>(newest - loss_window_first_ + 1);
  loss_share_ = std::clamp(1.0 - static_cast<double>(loss_window_received_) / expected, 0.0, 1.0);
  const double window_s = now_s - loss_window_start_s_;
  if (loss_share_ > kLossHigh) {
    // No higher than what arrived while the link dropped the rest: its
    // capacity, as far as this side can tell (GCC's acknowledged bitrate).
    loss_kbps_ =
        std::min(std::min(loss_kbps_, target_kbps()) * (1.0 - 0.5 * loss_share_), received_kbps_);
    cut_pending_ = true;
    next_feedback_s_ = std::min(next_feedback_s_, now_s);
  } else if (loss_share_ < kLossLow) {
    // Up while nothing is lost, but never far above what arrives (as the
    // delay-based estimate): an unused rate is no evidence of capacity.
    const double grown = loss_kbps_ * std::pow(kMultiplicativeGain, window_s);
    loss_kbps_ =
        std::min({config_.max_kbps, grown, std::max(loss_kbps_, 1.5 * received_kbps_ + 10.0)});
  }
  loss_kbps_ = std::clamp(loss_kbps_, config_.min_kbps, config_.max_kbps);
  loss_window_start_s_ = now_s;
  loss_window_first_ = newest + 1;
  loss_window_received_ = 0;
}

}  // namespace haptel::video
