#pragma once
/// @file The link's one-way delay as the predictive display needs it, from
/// command round trips (the vehicle echoes each command's send time and how
/// long it held it: no shared clock). Half the median of the last 15 round
/// trips, so that it follows a change of the link within a fraction of a
/// second and ignores single late packets. Shared by the robot's and the
/// blimp's predictors, and so is StampDating: when a state was sampled, on
/// the operator's clock.
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

/// When a stamped state was sampled, on the operator's clock. The vehicle's
/// clock is its own, so its offset is estimated as the smallest arrival
/// less stamp over the last few seconds less half the smallest round trip
/// (the minimum filter of clock synchronisation, as NTP's clock filter
/// keeps the sample of least delay: the fastest state crossed in the
/// fastest one-way time). A state that a loaded host delivered late is
/// then taken for as old as it is, not as fresh as its arrival says; never
/// dated after its arrival. Until a round trip is known, or unstamped, a
/// state is dated by its arrival less the one-way delay given.
class StampDating {
 public:
  /// Arrivals less stamps and round trips kept: 5 s of states at 50 Hz.
  static constexpr size_t kWindow = 250;
  /// A measured round trip (s); ignored unless finite and non-negative.
  void AddRoundTrip(double rtt_s);
  /// When the state that arrived at `received_s` (operator's clock) with
  /// `stamp_s` (the vehicle's clock; 0: unstamped) was sampled; notes its
  /// arrival less stamp for those after. `one_way_s`: the delay for an
  /// undated state.
  double SampleTime(double received_s, double stamp_s, double one_way_s);

 private:
  std::array<double, kWindow> transit_s_{};
  std::array<double, kWindow> rtt_s_{};
  size_t transits_ = 0, rtts_ = 0;
};

}  // namespace haptel::mediator
