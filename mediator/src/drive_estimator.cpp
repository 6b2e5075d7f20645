#include "haptel/mediator/drive_estimator.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "haptel/models/tread_drive.hpp"

namespace haptel::mediator {

namespace {

constexpr double kMinGain = 0.3, kMaxGain = 2.0;
constexpr double kMinWidthShare = 0.8, kMaxWidthShare = 3.0;

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
  if (!seeded_ || !(dt > 0.0) || dt > options_.max_gap_s) {
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
  if (std::abs(u_right_ - u_left_) > options_.min_turn * top) {
    const double clip = width_known_ ? options_.outlier_sds * per_width_.noise_sd()
                                     : std::numeric_limits<double>::infinity();
    const double yaw_residual =
        per_width_.Update(Eigen::Vector2d(-u_left_, u_right_), state.yaw_rate, clip);
    ++width_updates_;
    const double width = nominal_.track_width;
    const bool changed = state.stamp_s - gains_reset_at_s_ <= options_.changed_window_s;
    Guard(per_width_, options_.reset_covariance / (width * width), width_known_, yaw_residual,
          width_outliers_, changed ? options_.reset_run : options_.width_reset_run);
  }

  // Known once converged, and from then on (a reset or a stretch without
  // turns widens the covariance again; the estimate is still the best there is).
  if (!gains_known_ && Known(gains_)) {
    gains_known_ = true;
    gains_known_at_s_ = state.stamp_s;
  }
  if (gains_known_ && !width_known_ && Known(per_width_)) {
    width_known_ = true;
    width_known_at_s_ = state.stamp_s;
  }
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

double DriveEstimator::left_gain() const {
  return gains_known_ ? std::clamp(gains_.estimate()(0), kMinGain, kMaxGain) : nominal_.left_gain;
}

double DriveEstimator::right_gain() const {
  return gains_known_ ? std::clamp(gains_.estimate()(1), kMinGain, kMaxGain) : nominal_.right_gain;
}

double DriveEstimator::track_width() const {
  if (!width_known_) return nominal_.track_width;
  // g = B a for both treads: B by least squares.
  const Eigen::Vector2d& g = gains_.estimate();
  const Eigen::Vector2d& a = per_width_.estimate();
  return std::clamp(g.dot(a) / a.squaredNorm(), kMinWidthShare * nominal_.track_width,
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
