#pragma once
/// @file Recursive least squares with exponential forgetting, for two
/// parameters: y = φᵀθ + e, one scalar measurement at a time (Ljung, "System
/// Identification", 2nd ed. 1999, §11.2). What the predictors' estimators
/// (drive_estimator.hpp, the blimp's wind in blimp_predictor.hpp) are built
/// on.
///
/// The covariance P it keeps is the estimate's up to the measurements' noise
/// variance, which it tracks from the a-priori residuals with the same
/// memory (1/(1 − λ) measurements), never below `noise_floor`², so that a
/// noise-free drive is not taken as exact before its regressors span both
/// directions. Its guards are its user's to call: a bound on P's trace
/// (forgetting in a direction nothing excites grows it without end: "wind-up")
/// and a reset (the system changed). Allocates nothing.
#include <Eigen/Core>
#include <limits>

namespace haptel::mediator {

class RecursiveLeastSquares2 {
 public:
  /// `initial`: the estimate before any measurement (the prior), worth
  /// `initial_covariance` (large: nothing). `forgetting`: λ in (0, 1].
  RecursiveLeastSquares2(const Eigen::Vector2d& initial, double initial_covariance,
                         double forgetting, double noise_floor);

  /// One measurement; returns its a-priori residual y − φᵀθ. A residual
  /// over `max_residual` pulls (and counts in the noise) as if it were
  /// `max_residual`: Huber's M-estimator in recursive form (Huber, "Robust
  /// Statistics", 1981, ch. 7; Ljung 1999, §15.2), so that a burst of
  /// outliers moves the estimate by a bounded step each.
  /// `forget`: false for a measurement that excites one direction only, so
  /// that the other, which it says nothing of, is not forgotten either (a
  /// restricted form of directional forgetting: Kulhavý, "Restricted
  /// exponential forgetting in real-time identification", Automatica 1987).
  double Update(const Eigen::Vector2d& phi, double y,
                double max_residual = std::numeric_limits<double>::infinity(), bool forget = true);

  const Eigen::Vector2d& estimate() const { return theta_; }
  const Eigen::Matrix2d& covariance() const { return p_; }
  /// The measurements' noise as tracked (at least the floor).
  double noise_sd() const;
  /// Parameter i's standard deviation: the noise's times √P_ii.
  double StandardDeviation(int i) const;
  /// P scaled down to `max_trace` when its trace is over it.
  void BoundCovariance(double max_trace);
  /// P back to `covariance` × I, the estimate kept.
  void ResetCovariance(double covariance);

 private:
  Eigen::Vector2d theta_;
  Eigen::Matrix2d p_;
  double forgetting_;
  double noise_floor_;
  double noise_variance_;
};

}  // namespace haptel::mediator
