#include "haptel/mediator/recursive_least_squares.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::mediator {

RecursiveLeastSquares2::RecursiveLeastSquares2(const Eigen::Vector2d& initial,
                                               double initial_covariance, double forgetting,
                                               double noise_floor)
    : theta_(initial),
      p_(initial_covariance * Eigen::Matrix2d::Identity()),
      forgetting_(forgetting),
      noise_floor_(noise_floor),
      noise_variance_(noise_floor * noise_floor) {}

double RecursiveLeastSquares2::Update(const Eigen::Vector2d& phi, double y, double max_residual,
                                      bool forget) {
  const double residual = y - phi.dot(theta_);
  const double used = std::clamp(residual, -max_residual, max_residual);
  const double lambda = forget ? forgetting_ : 1.0;
  const Eigen::Vector2d p_phi = p_ * phi;
  const Eigen::Vector2d gain = p_phi / (lambda + phi.dot(p_phi));
  theta_ += gain * used;
  p_ = (p_ - gain * p_phi.transpose()) / lambda;
  p_ = 0.5 * (p_ + p_.transpose());  // kept symmetric against rounding
  noise_variance_ = forgetting_ * noise_variance_ + (1.0 - forgetting_) * used * used;
  return residual;
}

double RecursiveLeastSquares2::noise_sd() const {
  return std::sqrt(std::max(noise_variance_, noise_floor_ * noise_floor_));
}

double RecursiveLeastSquares2::StandardDeviation(int i) const {
  return noise_sd() * std::sqrt(std::max(p_(i, i), 0.0));
}

void RecursiveLeastSquares2::BoundCovariance(double max_trace) {
  if (const double trace = p_.trace(); trace > max_trace) p_ *= max_trace / trace;
}

void RecursiveLeastSquares2::ResetCovariance(double covariance) {
  p_ = covariance * Eigen::Matrix2d::Identity();
}

}  // namespace haptel::mediator
