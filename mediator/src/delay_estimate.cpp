#include "haptel/mediator/delay_estimate.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::mediator {

void DelayEstimate::AddRoundTrip(double rtt_s) {
  if (!std::isfinite(rtt_s) || rtt_s < 0.0) return;
  rtt_s_[next_] = rtt_s;
  next_ = (next_ + 1) % kWindow;
  count_ = std::min(count_ + 1, kWindow);
}

double DelayEstimate::one_way_s() const {
  if (count_ == 0) return 0.0;
  std::array<double, kWindow> sorted = rtt_s_;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(count_ / 2),
                   sorted.begin() + static_cast<long>(count_));
  return 0.5 * sorted[count_ / 2];
}

void StampDating::AddRoundTrip(double rtt_s) {
  if (std::isfinite(rtt_s) && rtt_s >= 0.0) rtt_s_[rtts_++ % kWindow] = rtt_s;
}

double StampDating::SampleTime(double received_s, double stamp_s, double one_way_s) {
  if (stamp_s == 0.0 || rtts_ == 0) return received_s - one_way_s;
  transit_s_[transits_++ % kWindow] = received_s - stamp_s;
  const double fastest_transit =
      *std::min_element(transit_s_.begin(), transit_s_.begin() + std::min(transits_, kWindow));
  const double fastest_rtt =
      *std::min_element(rtt_s_.begin(), rtt_s_.begin() + std::min(rtts_, kWindow));
  return std::min(received_s, stamp_s + fastest_transit - 0.5 * fastest_rtt);
}

}  // namespace haptel::mediator
