#pragma once
/// @file The haptic device interface the servo loop drives.
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

enum class DeviceStatus {
  kOk,       ///< fresh reading
  kNoData,   ///< no new reading this tick (keep the last one)
  kLost,     ///< the device stopped answering: forces must be zero
};

/// A force-feedback device with up to two arms. Read and WriteForce are called
/// from the servo thread only and must not allocate or block beyond the
/// device's own I/O.
class Device {
 public:
  virtual ~Device() = default;
  virtual bool HasSide(Side side) const = 0;
  /// Reads the hand on `side` at servo time `now_ns` into `out`.
  virtual DeviceStatus Read(Side side, int64_t now_ns, HandSample& out) = 0;
  /// Commands the wrist force on `side` (already limited by the servo loop).
  virtual DeviceStatus WriteForce(Side side, const Vec3d& force) = 0;
  /// Largest wrist force the device may be commanded, N.
  virtual double wrist_force_limit() const = 0;
};

}  // namespace haptel::haptics
