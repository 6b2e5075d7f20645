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

}  // namespace haptel::mediator
