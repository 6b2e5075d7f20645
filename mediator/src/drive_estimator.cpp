#include "haptel/mediator/drive_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "haptel/models/tread_drive.hpp"

namespace haptel::mediator {

namespace {

constexpr double kMinGain = 0.3, kMaxGain = 2.0;
constexpr double kMinWidthShare = 0.8, kMaxWidthShare = 3.0;
constexpr double kMinRatio = 0.5, kMaxRatio = 2.0;

}  // namespace

DriveEstimator::DriveEstimator(const TreadDriveConfig& nominal, const Options& options)
    : nominal_(nominal),
      options_(options),
      gains_({nominal.left_gain, nominal.right_gain}, options.initial_covariance,
             options.forgetting, options.speed_noise_floor),
      per_width_(Eigen::Vector2d(nominal.left_gain, nominal.right_gain) / nominal.track_width,
                 options.initial_covariance, options.forgetting, options.yaw_noise_floor) {}

void DriveEstimator::Observe(const DriveObservation& state) {
  const double top = nominal_.max_speed;
  const double target_left = models::LevelSpeed(nominal_, state.applied_left);
  const double target_right = models::LevelSpeed(nominal_, state.applied_right);
  const double dt = state.stamp_s - last_stamp_s_;
  const double tau = nominal_.motor_time_constant;
  // A state sampled no later than the last one (a vehicle that sends a
  // measurement a little older than the one before: harsh's state jitter
  // does, one state in eleven) is out of sequence: the lag is already past
  // it. It is left out, as out-of-sequence measurements are when they are
  // few (Bar-Shalom, "Update with out-of-sequence measurements", IEEE TAES
  // 2002, discusses the alternatives); taking it as a gap instead stopped
  // all learning for 10 time constants each, and on harsh for good.
  if (seeded_ && !(dt > 0.0)) return;
  if (!seeded_ || dt > options_.max_gap_s) {
    // The first state, one after a gap or after a bumper let go: the lag
    // taken as settled at the levels applied, and nothing learnt until it
    // would be (10 time constants: 5e-5 of a step left) unless at rest.
    u_left_ = target_left;
    u_right_ = target_right;
    last_stamp_s_ = state.stamp_s;
    settled_s_ = state.stamp_s + (target_left == 0.0 && target_right == 0.0 ? 0.0 : 10.0 * tau);
    seeded_ = true;
    return;
  }
  last_stamp_s_ = state.stamp_s;
  // The levels are taken as applied over the whole interval: a change
  // between two states is placed at the first (half a state period's error).
  const double alpha = tau > 0.0 ? 1.0 - std::exp(-dt / tau) : 1.0;
  u_left_ += (target_left - u_left_) * alpha;
  u_right_ += (target_right - u_right_) * alpha;

  if (state.touching) {
    // The treads stall against what it touches: their lag is not the model's
    // until they run free again.
    seeded_ = false;
    return;
  }
  const bool moving = std::max(std::abs(u_left_), std::abs(u_right_)) > options_.min_motion * top;
  if (!moving || state.stamp_s < settled_s_ || !std::isfinite(state.speed) ||
      !std::isfinite(state.yaw_rate))
    return;

  const double speed_residual =
      gains_.Update(Eigen::Vector2d(0.5 * u_left_, 0.5 * u_right_), state.speed);
  ++gain_updates_;
  if (Guard(gains_, options_.reset_covariance, gains_known_, speed_residual, gain_outliers_,
            options_.reset_run))
    gains_reset_at_s_ = state.stamp_s;
  // The yaw rate while driving straight shows the treads' difference
  // (a_r − a_l); while turning, their sum, which is the width.
  const bool turning = std::abs(u_right_ - u_left_) > options_.min_turn * top;
  if (turning) ++width_updates_;
  const double clip = width_known_ ? options_.outlier_sds * per_width_.noise_sd()
                                   : std::numeric_limits<double>::infinity();
  const double yaw_residual =
      per_width_.Update(Eigen::Vector2d(-u_left_, u_right_), state.yaw_rate, clip, turning);
  const double width = nominal_.track_width;
  const bool changed = state.stamp_s - gains_reset_at_s_ <= options_.changed_window_s;
  Guard(per_width_, options_.reset_covariance / (width * width), width_known_, yaw_residual,
        width_outliers_, changed ? options_.reset_run : options_.width_reset_run);

  // Known once converged, and from then on (a reset or a stretch without
  // turns widens the covariance again; the estimate is still the best there is).
  if (!gains_known_ && MeanGainSd() < options_.known_share * MeanGain()) {
    gains_known_ = true;
    gains_known_at_s_ = state.stamp_s;
  }
  if (!ratio_known_ && RatioSd() < options_.known_ratio_sd) {
    ratio_known_ = true;
    ratio_known_at_s_ = state.stamp_s;
  }
  if (gains_known_ && !width_known_ && Known(per_width_)) {
    width_known_ = true;
    width_known_at_s_ = state.stamp_s;
  }
}

double DriveEstimator::MeanGain() const {
  return 0.5 * (gains_.estimate()(0) + gains_.estimate()(1));
}

double DriveEstimator::MeanGainSd() const {
  const Eigen::Vector2d half(0.5, 0.5);
  return gains_.noise_sd() * std::sqrt(std::max(half.dot(gains_.covariance() * half), 0.0));
}

double DriveEstimator::Ratio() const {
  const Eigen::Vector2d& a = per_width_.estimate();
  return a(1) / a(0);
}

double DriveEstimator::RatioSd() const {
  // The delta method: ρ = a_r / a_l, ∇ρ = (−a_r / a_l², 1 / a_l).
  const Eigen::Vector2d& a = per_width_.estimate();
  if (!(a(0) > 0.0) || !(a(1) > 0.0)) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d grad(-a(1) / (a(0) * a(0)), 1.0 / a(0));
  return per_width_.noise_sd() * std::sqrt(std::max(grad.dot(per_width_.covariance() * grad), 0.0));
}

bool DriveEstimator::Known(const RecursiveLeastSquares2& rls) const {
  for (int i = 0; i < 2; ++i) {
    if (!(rls.StandardDeviation(i) < options_.known_share * std::abs(rls.estimate()(i))))
      return false;
  }
  return true;
}

bool DriveEstimator::Guard(RecursiveLeastSquares2& rls, double reset_covariance, bool known,
                           double residual, int& run, int reset_after) {
  // No wind-up: forgetting in a direction nothing excites grows it without end.
  rls.BoundCovariance(known ? 2.0 * reset_covariance : 2.0 * options_.initial_covariance);
  // The system changed when the residuals keep one sign, each over the
  // noise (by chance: 2^-24 for 25 in a row).
  const bool out = std::abs(residual) > rls.noise_sd();
  const int sign = residual > 0.0 ? 1 : -1;
  run = out ? (run * sign > 0 ? run + sign : sign) : 0;
  if (known && std::abs(run) >= reset_after) {
    rls.ResetCovariance(reset_covariance);
    run = 0;
    ++resets_;
    return true;
  }
  return false;
}

double DriveEstimator::gain_ratio() const {
  const double nominal = nominal_.right_gain / nominal_.left_gain;
  return ratio_known_ ? std::clamp(Ratio(), kMinRatio, kMaxRatio) : nominal;
}

double DriveEstimator::left_gain() const {
  if (!gains_known_) return nominal_.left_gain;
  return std::clamp(2.0 * MeanGain() / (1.0 + gain_ratio()), kMinGain, kMaxGain);
}

double DriveEstimator::right_gain() const {
  if (!gains_known_) return nominal_.right_gain;
  const double ratio = gain_ratio();
  return std::clamp(2.0 * MeanGain() * ratio / (1.0 + ratio), kMinGain, kMaxGain);
}

double DriveEstimator::track_width() const {
  if (!width_known_) return nominal_.track_width;
  // g_l + g_r = B (a_l + a_r): the mean gain's scale over the yaw's.
  const Eigen::Vector2d& a = per_width_.estimate();
  return std::clamp(2.0 * MeanGain() / (a(0) + a(1)), kMinWidthShare * nominal_.track_width,
                    kMaxWidthShare * nominal_.track_width);
}

TreadDriveConfig DriveEstimator::Drive() const {
  TreadDriveConfig drive = nominal_;
  drive.left_gain = left_gain();
  drive.right_gain = right_gain();
  drive.track_width = track_width();
  return drive;
}

}  // namespace haptel::mediator
