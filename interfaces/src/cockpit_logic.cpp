#include "haptel/interfaces/cockpit_logic.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "haptel/config/error.hpp"

namespace haptel::interfaces {

namespace {
constexpr double kDegToRad = std::numbers::pi / 180.0;
/// Indicators light past this share of the full-turn angle.
constexpr double kIndicatorShare = 0.15;
}  // namespace

CockpitLogic::CockpitLogic(const CockpitConfig& config) : config_(Validated(config)) {}

TreadCommand CockpitLogic::Map(const CockpitControls& c, double t_s) const {
  const double full = config_.wheel_full_turn_deg * kDegToRad;
  const double turn = config_.turn_share * std::clamp(c.wheel_angle / full, -1.0, 1.0);
  const double forward =
      throttle_locked(t_s) ? 0.0 : std::clamp(c.throttle / config_.throttle_travel, -1.0, 1.0);
  return Mix(forward, turn);
}

CockpitControls CockpitLogic::ControlsFor(const MotionIntent& intent) const {
  CockpitControls c;
  const double full = config_.wheel_full_turn_deg * kDegToRad;
  c.wheel_angle =
      config_.turn_share > 0 ? std::clamp(intent.turn / config_.turn_share, -1.0, 1.0) * full : 0.0;
  c.throttle = std::clamp(intent.forward, -1.0, 1.0) * config_.throttle_travel;
  c.wheel_held = c.throttle_held = true;
  return c;
}

ControlActuation CockpitLogic::Update(double t_s, const VehicleFeedback& feedback,
                                      const CockpitControls& controls) {
  const bool touching = feedback.bumper_left || feedback.bumper_right;
  if (touching && !was_touching_) {
    shake_start_s_ = t_s;
    shake_until_s_ = t_s + config_.shake_s;
    lock_until_s_ = t_s + config_.throttle_lock_s;
  }
  was_touching_ = touching;

  ControlActuation a;
  if (shaking(t_s)) {
    a.wheel_torque = config_.shake_torque *
                     std::sin(2.0 * std::numbers::pi * config_.shake_hz * (t_s - shake_start_s_));
  }
  if (throttle_locked(t_s)) {
    a.throttle_locked = true;
    a.throttle_target = 0.0;
  } else if (config_.return_to_zero && !controls.throttle_held) {
    a.throttle_spring = config_.throttle_return_stiffness;
  }
  if (config_.return_to_zero && !controls.wheel_held)
    a.wheel_spring = config_.wheel_return_stiffness;
  return a;
}

HudState CockpitLogic::Hud(const VehicleFeedback& feedback, const CockpitControls& controls,
                           double t_s) const {
  HudState h;
  if (!config_.hud) return h;
  h.speed = feedback.speed;
  const double threshold = kIndicatorShare * config_.wheel_full_turn_deg * kDegToRad;
  h.turn_left = controls.wheel_angle > threshold;
  h.turn_right = controls.wheel_angle < -threshold;
  h.throttle_locked = throttle_locked(t_s);
  return h;
}

}  // namespace haptel::interfaces
