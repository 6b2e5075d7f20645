#include "haptel/haptics/safety.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/haptics/force_field.hpp"

namespace haptel::haptics {

ForceSafety::ForceSafety(const SafetyConfig& config, double device_wrist_limit,
                         double device_finger_limit)
    : config_(Validated(config)),
      wrist_limit_(std::min(config.wrist_force_limit, device_wrist_limit)),
      finger_limit_(std::min(config.finger_force_limit, device_finger_limit)) {}

void ForceSafety::OnConnect(int64_t now_ns) {
  connected_ = true;
  connect_ns_ = now_ns;
  last_ns_ = now_ns;
  last_wrist_ = Vec3d{};
  last_fingers_ = {};
}

void ForceSafety::OnLost() {
  connected_ = false;
  last_wrist_ = Vec3d{};
  last_fingers_ = {};
}

double ForceSafety::FadeGain(int64_t now_ns, int64_t setpoint_stamp_ns) const {
  if (setpoint_stamp_ns == 0) return 0.0;
  const double age = static_cast<double>(now_ns - setpoint_stamp_ns) * 1e-9;
  if (age <= config_.setpoint_timeout_s) return 1.0;
  if (config_.fade_s <= 0.0) return 0.0;
  return std::clamp(1.0 - (age - config_.setpoint_timeout_s) / config_.fade_s, 0.0, 1.0);
}

double ForceSafety::SoftStartGain(int64_t now_ns) const {
  if (!connected_) return 0.0;
  if (config_.soft_start_s <= 0.0) return 1.0;
  return std::clamp(static_cast<double>(now_ns - connect_ns_) * 1e-9 / config_.soft_start_s, 0.0,
                    1.0);
}

void ForceSafety::Apply(int64_t now_ns, int64_t setpoint_stamp_ns, const Vec3d& setpoint_wrist,
                        const Vec3d& local_wrist, Vec3d& wrist,
                        std::array<double, kFingers>& fingers) {
  if (!connected_) {
    wrist = Vec3d{};
    fingers = {};
    return;
  }
  const double fade = FadeGain(now_ns, setpoint_stamp_ns);
  // A set-point never written is absent, not stale: no force, and nothing to count.
  if (fade < 1.0 && setpoint_stamp_ns != 0) ++counters_.stale_ticks;
  for (int i = 0; i < 3; ++i) wrist[i] = fade * setpoint_wrist[i] + local_wrist[i];
  for (double& f : fingers) f *= fade;

  bool non_finite = false;
  for (double c : wrist) non_finite |= !std::isfinite(c);
  if (non_finite) wrist = Vec3d{};
  for (double& f : fingers) {
    if (!std::isfinite(f)) {
      f = 0.0;
      non_finite = true;
    }
  }
  if (non_finite) ++counters_.non_finite;

  bool clamped = LimitForce(wrist, wrist_limit_);
  for (double& f : fingers) {
    const double limited = std::clamp(f, 0.0, finger_limit_);  // strings only pull
    clamped |= limited != f && f > 0.0;
    f = limited;
  }
  if (clamped) ++counters_.clamped;

  const double soft = SoftStartGain(now_ns);
  for (double& c : wrist) c *= soft;
  for (double& f : fingers) f *= soft;

  // A tick at the same instant as the last (e.g. right at connect) still gets
  // a sliver of rate, so the limit never freezes the output.
  const double dt = std::max(1e-4, static_cast<double>(now_ns - last_ns_) * 1e-9);
  const double step = config_.max_force_rate * dt;
  bool limited = false;
  for (int i = 0; i < 3; ++i) {
    const double d = std::clamp(wrist[i] - last_wrist_[i], -step, step);
    limited |= d != wrist[i] - last_wrist_[i];
    wrist[i] = last_wrist_[i] + d;
  }
  for (int k = 0; k < kFingers; ++k) {
    const double d = std::clamp(fingers[k] - last_fingers_[k], -step, step);
    limited |= d != fingers[k] - last_fingers_[k];
    fingers[k] = last_fingers_[k] + d;
  }
  if (limited) ++counters_.rate_limited;
  last_ns_ = now_ns;
  last_wrist_ = wrist;
  last_fingers_ = fingers;
}

}  // namespace haptel::haptics
