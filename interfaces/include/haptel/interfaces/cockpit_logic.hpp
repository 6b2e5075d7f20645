#pragma once
/// @file What the cockpit interfaces do with their controls, apart from the
/// physics that moves them: the mapping from wheel and throttle to motors,
/// the reaction to a bumper contact (wheel shake, throttle lock), the
/// return-to-zero springs of the assisted cockpit, and the HUD values.
///
/// The physics world owns the wheel and lever bodies and applies the
/// ControlActuation this computes; the logic itself is plain and testable.
#include "haptel/config/cockpit.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::interfaces {

/// The controls as the physics world reports them.
struct CockpitControls {
  double wheel_angle = 0.0;  ///< rad, positive = turned left (counter-clockwise seen by the driver)
  double throttle = 0.0;     ///< lever position, m from centre, positive = forward
  bool wheel_held = false;   ///< a hand grasps the rim
  bool throttle_held = false;  ///< a hand grasps the lever
};

/// What the physics world must apply to the controls this tick.
struct ControlActuation {
  double wheel_torque = 0.0;     ///< N·m about the hinge (shake)
  double wheel_spring = 0.0;     ///< N·m/rad toward 0 (return to zero)
  double throttle_spring = 0.0;  ///< N/m toward `throttle_target`
  double throttle_target = 0.0;  ///< m
  bool throttle_locked = false;  ///< hold the lever at throttle_target rigidly

  /// Haptic shared control (cockpit-shared; shared_control.hpp): a spring
  /// past a plane in the controls' space — the lever's travel (m) and the
  /// rim's arc, wheel angle × wheel radius (m) — pushing the controls back
  /// from the commands that lead into an obstacle, up to
  /// guidance_max_force: a force on the lever, a torque (force × radius)
  /// on the wheel. Evaluated in physics at every step from the controls'
  /// positions, so it acts at the physics rate however often this is set
  /// (physics/cockpit_controls.hpp; damped there for the controls' mass).
  bool guidance_active = false;
  double guidance_throttle = 0.0;         ///< m: the plane's point, lever
  double guidance_wheel_angle = 0.0;      ///< rad: the plane's point, wheel
  double guidance_normal_throttle = 1.0;  ///< the plane's unit normal, towards danger: lever part
  double guidance_normal_rim = 0.0;       ///< ...and rim part (+ = turned left)
  double guidance_stiffness = 0.0;        ///< N/m past the plane
  double guidance_max_force = 0.0;        ///< N: the most it pushes
};

/// View elements of the HUD cockpits.
struct HudState {
  double speed = 0.0;      ///< m/s, the vehicle's reported speed
  bool turn_left = false;  ///< indicator lights
  bool turn_right = false;
  bool throttle_locked = false;
};

class CockpitLogic {
 public:
  /// Validates `config` first (CockpitConfig::ValidateOrThrow: ConfigFieldError).
  explicit CockpitLogic(const CockpitConfig& config);

  /// Wheel → turn, throttle → forward; zero forward while the throttle is locked.
  TreadCommand Map(const CockpitControls& controls, double t_s) const;
  /// Reacts to the vehicle (a new bumper contact starts shake and lock) and
  /// returns what the controls must feel now.
  ControlActuation Update(double t_s, const VehicleFeedback& feedback,
                          const CockpitControls& controls);
  HudState Hud(const VehicleFeedback& feedback, const CockpitControls& controls, double t_s) const;

  /// The control positions that express an intent (inverse of Map).
  CockpitControls ControlsFor(const MotionIntent& intent) const;

  bool shaking(double t_s) const { return t_s < shake_until_s_; }
  bool throttle_locked(double t_s) const { return t_s < lock_until_s_; }
  const CockpitConfig& config() const { return config_; }

 private:
  CockpitConfig config_;
  bool was_touching_ = false;
  double shake_start_s_ = -1e9;
  double shake_until_s_ = -1e9;
  double lock_until_s_ = -1e9;
};

}  // namespace haptel::interfaces
