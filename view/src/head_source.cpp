#include "haptel/view/head_source.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/core/blimp_command.hpp"
#include "haptel/interfaces/gamepad.hpp"

namespace haptel::view {

namespace {

HeadPose Clamped(HeadPose p) {
  return {std::clamp(p.pan, -kBlimpCameraPanMax, kBlimpCameraPanMax),
          std::clamp(p.tilt, -kBlimpCameraTiltMax, kBlimpCameraTiltMax)};
}

}  // namespace

GamepadHead::GamepadHead(const HeadConfig& config, const interfaces::InputState& at_start)
    : config_(config), disconnects_seen_(at_start.pad_disconnects) {}

HeadPose GamepadHead::Update(double t_s, const interfaces::InputState& s) {
  using interfaces::PadAxis;
  using interfaces::PadButton;
  const double dt = last_t_s_ < 0.0 ? 0.0 : std::clamp(t_s - last_t_s_, 0.0, 0.1);
  last_t_s_ = t_s;
  // Unplugged: the head holds where it looked until a controller is back.
  if (s.pad_disconnects != disconnects_seen_) {
    disconnects_seen_ = s.pad_disconnects;
    lost_ = true;
  }
  connected_ = s.pad_connected;
  if (!s.pad_connected) return pose_;
  lost_ = false;
  const auto axis = [&s](PadAxis a) { return s.pad_axes[static_cast<size_t>(a)]; };
  const bool recentre = s.pad_buttons[static_cast<size_t>(PadButton::kRightStick)];
  if (recentre && !recentre_held_) pose_ = {};
  recentre_held_ = recentre;
  const auto stick = interfaces::RadialDeadZone(axis(PadAxis::kRightX), axis(PadAxis::kRightY),
                                                config_.stick_dead_zone);
  // SDL's stick: x + right, y + down. Pushed right looks right (pan is
  // positive left); pushed up looks up.
  pose_ = Clamped({pose_.pan - stick[0] * config_.stick_rate_rad_s * dt,
                   pose_.tilt - stick[1] * config_.stick_rate_rad_s * dt});
  return pose_;
}

const char* GamepadHead::Notice() const {
  if (lost_) return kLostNotice;
  return connected_ ? nullptr : kNoControllerNotice;
}

HeadPose HeadPoseOfOrientation(double qx, double qy, double qz, double qw) {
  // The view's forward (-z) turned by q: the third column of its rotation, negated.
  const double fx = -(2.0 * (qx * qz + qw * qy));
  const double fy = -(2.0 * (qy * qz - qw * qx));
  const double fz = -(1.0 - 2.0 * (qx * qx + qy * qy));
  // OpenXR's x right, y up, -z ahead: looking left is -x, so pan = atan2(-x, -z).
  return Clamped({std::atan2(-fx, -fz), std::asin(std::clamp(fy, -1.0, 1.0))});
}

MadeHeadSource MakeHeadSource(const HeadConfig& config, const interfaces::InputState& at_start) {
  MadeHeadSource made;
  switch (config.source) {
    case HeadSourceKind::kGamepad:
      made.source = std::make_unique<GamepadHead>(config, at_start);
      return made;
    case HeadSourceKind::kOpenXr: {
      std::string why_not;
      made.source = OpenOpenXrHead(why_not);
      if (made.source) return made;
      made.fallback = why_not + ": head follows the mouse";
      break;
    }
    case HeadSourceKind::kMouse:
      break;
  }
  made.source = std::make_unique<MouseHead>();
  return made;
}

}  // namespace haptel::view
