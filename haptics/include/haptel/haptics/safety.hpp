#pragma once
/// @file Force safety for one arm, applied by the servo loop to every force
/// before it reaches the device. Allocation-free; counts instead of logging.
///
/// In order: set-point forces fade to zero when their feeder stalls
/// (older than `setpoint_timeout_s`, gone after `fade_s` more); local forces
/// (gravity compensation) are added; non-finite forces become zero; each force
/// is clamped to its limit; everything ramps in over `soft_start_s` after a
/// (re)connect; each axis and finger changes at most `max_force_rate` N/s.
/// A lost device gets zero at once, bypassing the ramp.
#include <array>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

struct SafetyCounters {
  uint64_t non_finite = 0;    ///< ticks with a NaN/Inf force (zeroed)
  uint64_t clamped = 0;       ///< ticks a force was limited to its maximum
  uint64_t rate_limited = 0;  ///< ticks a force change was slowed
  uint64_t stale_ticks = 0;   ///< ticks with a set-point gone stale (fading or faded)
};

class ForceSafety {
 public:
  /// Limits are the smaller of the configured and the device's own. Validates
  /// `config` first (SafetyConfig::ValidateOrThrow: ConfigFieldError).
  ForceSafety(const SafetyConfig& config, double device_wrist_limit, double device_finger_limit);

  /// The device (re)connected at `now_ns`: forces ramp in from zero.
  void OnConnect(int64_t now_ns);
  /// The device is lost: forces are zero now and ramp in again after reconnect.
  void OnLost();

  /// Computes the forces to command at `now_ns`. `setpoint_wrist` and
  /// `fingers` come from a set-point stamped `setpoint_stamp_ns` (0: never
  /// set); `local_wrist` is computed in the servo loop itself and never fades.
  /// Results are written back into `wrist` and `fingers`.
  void Apply(int64_t now_ns, int64_t setpoint_stamp_ns, const Vec3d& setpoint_wrist,
             const Vec3d& local_wrist, Vec3d& wrist, std::array<double, kFingers>& fingers);

  /// 1 while set-points are fresh, falling to 0 as they go stale.
  double FadeGain(int64_t now_ns, int64_t setpoint_stamp_ns) const;
  /// 0 at connect, rising to 1 after soft_start_s.
  double SoftStartGain(int64_t now_ns) const;

  const SafetyCounters& counters() const { return counters_; }
  double wrist_limit() const { return wrist_limit_; }
  double finger_limit() const { return finger_limit_; }

 private:
  SafetyConfig config_;
  double wrist_limit_;
  double finger_limit_;
  bool connected_ = false;
  int64_t connect_ns_ = 0;
  int64_t last_ns_ = 0;
  Vec3d last_wrist_{};
  std::array<double, kFingers> last_fingers_{};
  SafetyCounters counters_;
};

}  // namespace haptel::haptics
