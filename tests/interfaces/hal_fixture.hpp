#pragma once
/// @file A HAL for interface tests: raw tracker units are metres, and a
/// wrist sample can be put on either side directly.
#include <cstdint>

#include "haptel/haptics/hal.hpp"

namespace haptel::test {

/// Tracker scale 1, offset 0: what is published is metres.
inline DeviceCalibration Metres() {
  DeviceCalibration c;
  for (auto& a : c.arms) a.tracker_scale = {1, 1, 1};
  return c;
}

/// Publishes a wrist sample at `p` (m) on `side`, stamped `t_ns`.
inline void PutHand(haptics::Hal& hal, const haptics::Vec3d& p,
                    haptics::Side side = haptics::Side::kRight, int64_t t_ns = 1) {
  haptics::WristRaw w;
  w.t_ns = t_ns;
  w.position = p;
  hal.PublishWrist(side, w);
}

}  // namespace haptel::test
