#include "haptel/vehicles/command_watchdog.hpp"

#include <stdexcept>

namespace haptel::vehicles {

CommandWatchdog::CommandWatchdog(double timeout_s)
    : timeout_ns_(static_cast<int64_t>(timeout_s * 1e9)) {
  if (!(timeout_s > 0.0)) throw std::invalid_argument("CommandWatchdog: timeout must be > 0");
}

void CommandWatchdog::Feed(int64_t now_ns) {
  last_feed_ns_ = now_ns;
  fed_ = true;
}

bool CommandWatchdog::Expired(int64_t now_ns) const {
  return !fed_ || now_ns - last_feed_ns_ > timeout_ns_;
}

bool CommandWatchdog::Check(int64_t now_ns) {
  const bool expired = Expired(now_ns);
  if (expired && !was_expired_) ++trips_;
  was_expired_ = expired;
  return expired;
}

}  // namespace haptel::vehicles
