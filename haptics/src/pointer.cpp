#include "haptel/haptics/pointer.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::haptics {

PointerBox& DesktopPointer() {
  static PointerBox box;
  return box;
}

Vec3d PointerTarget(const PointerState& pointer, const MouseDeviceConfig& config) {
  const double m = config.metres_per_pixel;
  const double dx_px = pointer.x_px - 0.5 * pointer.width_px;
  const double dy_px = pointer.y_px - 0.5 * pointer.height_px;
  return {config.centre[0] - dy_px * m, config.centre[1] - dx_px * m,
          config.centre[2] + static_cast<double>(pointer.wheel_notches) * config.wheel_step};
}

std::array<int, 2> PointerPixelFor(const Vec3d& target, const MouseDeviceConfig& config,
                                   int width_px, int height_px) {
  const double m = config.metres_per_pixel;
  const double x = 0.5 * width_px - (target[1] - config.centre[1]) / m;
  const double y = 0.5 * height_px - (target[0] - config.centre[0]) / m;
  return {static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y))};
}

Vec3d StepKeyHand(const Vec3d& now, const PointerState& pointer, const MouseDeviceConfig& config,
                  double dt_s) {
  Vec3d next = now;
  const double step = config.key_hand_speed * std::max(0.0, dt_s);
  for (int axis = 0; axis < 3; ++axis) {
    const bool plus = pointer.key_hand[static_cast<size_t>(2 * axis)];
    const bool minus = pointer.key_hand[static_cast<size_t>(2 * axis + 1)];
    if (plus && !minus) {
      next[axis] += step;
    } else if (minus && !plus) {
      next[axis] -= step;
    } else if (!plus && !minus) {
      const double to_rest = config.key_hand_rest[axis] - now[axis];
      next[axis] += std::clamp(to_rest, -step, step);
    }
  }
  return next;
}

}  // namespace haptel::haptics
