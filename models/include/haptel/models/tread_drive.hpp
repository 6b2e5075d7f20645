#pragma once
/// @file The tank robot's drive as a model: two treads, each following its
/// target speed with a first-order lag and its own gain, and the body moving
/// on the exact constant-curvature arc they give. The simulated robot moves
/// by it (before its contacts), and the operator's predictor runs it ahead
/// of the delayed states, so the two cannot drift apart. It lives in
/// haptel_models, below both ends: the operator side links it without the
/// vehicles, and the vehicles without the operator side.
#include "haptel/config/vehicle.hpp"

namespace haptel::models {

/// Signed speed levels per motor, as the robot's brick takes them.
struct MotorLevels {
  int left = 0;
  int right = 0;
};

/// Maps a normalised command in [-1, 1] to the nearest of `levels` speed
/// levels in each direction (−levels..levels). Out-of-range commands are
/// clamped; NaN maps to 0 (stop).
int QuantiseCommand(double command, int levels);

/// The drive's state: the body's pose in the track frame and the treads'
/// speeds (m/s).
struct TreadState {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
  double v_left = 0.0;
  double v_right = 0.0;
};

/// The treads' target speeds (m/s) for speed levels, before the gains.
inline double LevelSpeed(const TreadDriveConfig& drive, int level) {
  return level * (drive.max_speed / drive.speed_levels);
}

/// Advances `state` by `dt` towards tread targets (m/s, before the gains):
/// each tread follows with the motor lag, then the body moves on the arc.
/// Returns the yaw rate (rad/s) over the step.
double StepTreads(const TreadDriveConfig& drive, double target_left, double target_right, double dt,
                  TreadState& state);

/// Moves the body in `state` by `dt` on the exact arc of forward speed `v`
/// and yaw rate `omega` (what StepTreads does after the lag).
void MoveOnArc(double v, double omega, double dt, TreadState& state);

/// The treads' speeds from a body's forward speed and yaw rate.
inline void TreadsFromMotion(const TreadDriveConfig& drive, double speed, double yaw_rate,
                             TreadState& state) {
  state.v_left = speed - 0.5 * yaw_rate * drive.track_width;
  state.v_right = speed + 0.5 * yaw_rate * drive.track_width;
}

}  // namespace haptel::models
