#pragma once
/// @file What a blimp is told, in semantic terms: the thesis's seven servo
/// channels (ch. 8.2.1) before any calibration to pulse widths. A flat value
/// type shared by the interfaces that make it, the automatic pilot, the DDS
/// link that carries it and the vehicle that obeys it.
#include <algorithm>
#include <cmath>

namespace haptel {

struct BlimpCommand {
  double elevator = 0.0;     ///< -1..1 of full travel; positive: nose up
  double rudder = 0.0;       ///< -1..1; positive: turn left
  double power = 0.0;        ///< 0..1 of both main motors' full thrust
  double helix = 0.0;        ///< -1..1 of the helix plane's tilt; positive: thrust tilts up (climb)
  double tail_rotor = 0.0;   ///< -1..1 of the reversible tail rotor; positive: turn left
  double camera_pan = 0.0;   ///< rad, positive: look left
  double camera_tilt = 0.0;  ///< rad, positive: look up
};

/// The pilot camera's mechanical range (a standard pan/tilt head).
constexpr double kBlimpCameraPanMax = 1.5708;   ///< rad each way (±90°)
constexpr double kBlimpCameraTiltMax = 0.7854;  ///< rad each way (±45°)

/// Whether every value is finite and within its range, widened by `slack`
/// at each end (a float's rounding past an end is not malformed). What a vehicle accepts; anything
/// else is a malformed command, counted and dropped.
inline bool InRange(const BlimpCommand& c, double slack = 0.0) {
  auto in = [slack](double v, double lo, double hi) {
    return std::isfinite(v) && v >= lo - slack && v <= hi + slack;
  };
  return in(c.elevator, -1, 1) && in(c.rudder, -1, 1) && in(c.power, 0, 1) && in(c.helix, -1, 1) &&
         in(c.tail_rotor, -1, 1) && in(c.camera_pan, -kBlimpCameraPanMax, kBlimpCameraPanMax) &&
         in(c.camera_tilt, -kBlimpCameraTiltMax, kBlimpCameraTiltMax);
}

/// The same command with every value clamped into its range (NaN → neutral).
inline BlimpCommand Clamped(const BlimpCommand& c) {
  auto clamp = [](double v, double lo, double hi) {
    return std::isfinite(v) ? std::clamp(v, lo, hi) : 0.0;
  };
  BlimpCommand out;
  out.elevator = clamp(c.elevator, -1, 1);
  out.rudder = clamp(c.rudder, -1, 1);
  out.power = clamp(c.power, 0, 1);
  out.helix = clamp(c.helix, -1, 1);
  out.tail_rotor = clamp(c.tail_rotor, -1, 1);
  out.camera_pan = clamp(c.camera_pan, -kBlimpCameraPanMax, kBlimpCameraPanMax);
  out.camera_tilt = clamp(c.camera_tilt, -kBlimpCameraTiltMax, kBlimpCameraTiltMax);
  return out;
}

}  // namespace haptel
