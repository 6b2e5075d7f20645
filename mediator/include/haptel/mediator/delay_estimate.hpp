#pragma once
/// @file The link's one-way delay as the predictive display needs it, from
/// command round trips (the vehicle echoes each command's send time and how
/// long it held it: no shared clock). Half the median of the last 15 round
/// trips, so that it follows a change of the link within a fraction of a
/// second and ignores single late packets. Shared by the robot's and the
/// blimp's predictors.
#include <array>
#include <cstddef>

namespace haptel::mediator {

/// The one-way delay from round trips: half their running median.
class DelayEstimate {
 public:
  static constexpr size_t kWindow = 15;
  /// A measured round trip (s); ignored unless finite and non-negative.
  void AddRoundTrip(double rtt_s);
  /// Half the median of the last kWindow round trips (0 before any).
  double one_way_s() const;
  size_t samples() const { return count_; }

 private:
  std::array<double, kWindow> rtt_s_{};
  size_t count_ = 0;
  size_t next_ = 0;
};

}  // namespace haptel::mediator
