#pragma once
/// @file Where a steerable camera points (pan, tilt, zoom), and the ranges
/// its head and lens allow. A flat value type shared by the station that
/// makes it, the DDS link that carries it (link/families.hpp: CameraMessages)
/// and the vehicle that applies it.
#include <algorithm>
#include <cmath>

namespace haptel {

struct CameraAim {
  double pan = 0.0;   ///< rad, positive: look left
  double tilt = 0.0;  ///< rad, positive: look up
  double zoom = 1.0;  ///< 1: widest; the field of view is the widest divided by this
};

/// What a camera's head and lens allow. A fixed camera: every span empty
/// (min == max == 0) and zoom_max 1.
struct CameraRange {
  double pan_min = 0.0;  ///< rad
  double pan_max = 0.0;
  double tilt_min = 0.0;  ///< rad
  double tilt_max = 0.0;
  double zoom_max = 1.0;  ///< ≥ 1

  bool pans() const { return pan_max > pan_min; }
  bool tilts() const { return tilt_max > tilt_min; }
  bool zooms() const { return zoom_max > 1.0; }
};

/// Whether every value of `aim` is finite and within `range`, widened by
/// `slack` at each end (a float's rounding past an end is not out of range).
inline bool InRange(const CameraAim& aim, const CameraRange& range, double slack = 0.0) {
  auto in = [slack](double v, double lo, double hi) {
    return std::isfinite(v) && v >= lo - slack && v <= hi + slack;
  };
  return in(aim.pan, range.pan_min, range.pan_max) &&
         in(aim.tilt, range.tilt_min, range.tilt_max) && in(aim.zoom, 1.0, range.zoom_max);
}

/// `aim` clamped into `range` (NaN → the range's centre, zoom 1).
inline CameraAim Clamped(const CameraAim& aim, const CameraRange& range) {
  auto clamp = [](double v, double lo, double hi, double otherwise) {
    return std::isfinite(v) ? std::clamp(v, lo, hi) : otherwise;
  };
  return {clamp(aim.pan, range.pan_min, range.pan_max, 0.5 * (range.pan_min + range.pan_max)),
          clamp(aim.tilt, range.tilt_min, range.tilt_max, 0.5 * (range.tilt_min + range.tilt_max)),
          clamp(aim.zoom, 1.0, range.zoom_max, 1.0)};
}

/// The horizontal field of view (degrees) of a lens whose widest is
/// `widest_deg`, at `zoom`: the focal length grows with the zoom, so the
/// tangent of the half angle shrinks by it (60° at 1× is 6.6° at 10×).
inline double ZoomedFovDeg(double widest_deg, double zoom) {
  constexpr double kDegPerRad = 57.29577951308232;
  const double half = 0.5 * widest_deg / kDegPerRad;
  return 2.0 * std::atan(std::tan(half) / std::max(zoom, 1.0)) * kDegPerRad;
}

}  // namespace haptel
