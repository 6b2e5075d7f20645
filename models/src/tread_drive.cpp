#include "haptel/models/tread_drive.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/core/geometry2d.hpp"

namespace haptel::models {

int QuantiseCommand(double command, int levels) {
  if (!std::isfinite(command)) return 0;
  const double clamped = std::clamp(command, -1.0, 1.0);
  return static_cast<int>(std::lround(clamped * levels));
}

double StepTreads(const TreadDriveConfig& drive, double target_left, double target_right, double dt,
                  TreadState& state) {
  if (!(dt > 0.0)) return 0.0;
  const double alpha =
      drive.motor_time_constant > 0 ? 1.0 - std::exp(-dt / drive.motor_time_constant) : 1.0;
  state.v_left += (target_left * drive.left_gain - state.v_left) * alpha;
  state.v_right += (target_right * drive.right_gain - state.v_right) * alpha;
  const double v = 0.5 * (state.v_left + state.v_right);
  const double omega = (state.v_right - state.v_left) / drive.track_width;
  MoveOnArc(v, omega, dt, state);
  return omega;
}

void MoveOnArc(double v, double omega, double dt, TreadState& state) {
  // Exact integration of a constant-curvature arc over dt.
  const double h0 = state.heading;
  const double h1 = h0 + omega * dt;
  if (std::abs(omega) > 1e-9) {
    state.x += v / omega * (std::sin(h1) - std::sin(h0));
    state.y -= v / omega * (std::cos(h1) - std::cos(h0));
  } else {
    state.x += v * dt * std::cos(h0);
    state.y += v * dt * std::sin(h0);
  }
  state.heading = WrapAngle(h1);
}

}  // namespace haptel::models
