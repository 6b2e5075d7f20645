#include "haptel/station/camera_control.hpp"

#include <cmath>

namespace haptel::station {

using interfaces::Key;
using interfaces::PadAxis;

namespace {

constexpr double kRadPerDeg = 0.017453292519943295;

/// `v` with the dead zone cut out, rescaled so full travel is still 1.
double Live(double v, double dead_zone) {
  const double magnitude = std::abs(v);
  if (magnitude <= dead_zone) return 0.0;
  return std::copysign((magnitude - dead_zone) / (1.0 - dead_zone), v);
}

}  // namespace

CameraControl::CameraControl(const CameraRange& range, double widest_fov_deg,
                             const CameraAim& start, const CameraControlRates& rates)
    : range_(range), widest_fov_deg_(widest_fov_deg), rates_(rates), aim_(Clamped(start, range)) {}

void CameraControl::SetCamera(const CameraRange& range, double widest_fov_deg) {
  range_ = range;
  widest_fov_deg_ = widest_fov_deg;
  aim_ = Clamped(aim_, range_);
}

void CameraControl::Set(const CameraAim& aim) { aim_ = Clamped(aim, range_); }

double CameraControl::FovRad() const {
  return ZoomedFovDeg(widest_fov_deg_, aim_.zoom) * kRadPerDeg;
}

const CameraAim& CameraControl::Step(const interfaces::InputState& input,
                                     const haptics::PointerState& pointer, double dt_s) {
  const double fov = FovRad();
  double pan = aim_.pan;
  double tilt = aim_.tilt;
  double zoom_log = std::log(aim_.zoom);

  // Dragging the picture: the scene follows the pointer (right: what was
  // on the left comes into view, the camera looks left).
  const bool pressed = pointer.window_open && pointer.grasp_button;
  if (pressed && dragging_ && pointer.width_px > 0) {
    const double per_px = fov / pointer.width_px;
    pan += (pointer.x_px - last_x_) * per_px;
    tilt += (pointer.y_px - last_y_) * per_px;
  }
  dragging_ = pressed;
  last_x_ = pointer.x_px;
  last_y_ = pointer.y_px;

  if (wheel_known_) {
    zoom_log += static_cast<double>(pointer.wheel_notches - last_wheel_) * std::log(kWheelZoomStep);
  }
  wheel_known_ = true;
  last_wheel_ = pointer.wheel_notches;

  const auto held = [&input](Key k) { return input.keys_held[static_cast<size_t>(k)] ? 1.0 : 0.0; };
  const auto axis = [&input](PadAxis a) { return input.pad_axes[static_cast<size_t>(a)]; };
  const double key_pan = std::min(1.0, held(Key::kArrowLeft) + held(Key::kA)) -
                         std::min(1.0, held(Key::kArrowRight) + held(Key::kD));
  const double key_tilt = std::min(1.0, held(Key::kArrowUp) + held(Key::kW)) -
                          std::min(1.0, held(Key::kArrowDown) + held(Key::kS));
  const double key_zoom = held(Key::kPageUp) - held(Key::kPageDown);
  pan += key_pan * rates_.key_rate * fov * dt_s;
  tilt += key_tilt * rates_.key_rate * fov * dt_s;
  zoom_log += key_zoom * std::log(rates_.zoom_rate) * dt_s;

  if (input.pad_connected) {
    // SDL's sticks: x right and y down positive; the camera's pan is left
    // and its tilt up positive.
    pan -= Live(axis(PadAxis::kLeftX), rates_.dead_zone) * rates_.stick_rate * fov * dt_s;
    tilt -= Live(axis(PadAxis::kLeftY), rates_.dead_zone) * rates_.stick_rate * fov * dt_s;
    const double pad_zoom = Live(axis(PadAxis::kTriggerRight), rates_.dead_zone) -
                            Live(axis(PadAxis::kTriggerLeft), rates_.dead_zone) -
                            Live(axis(PadAxis::kRightY), rates_.dead_zone);
    zoom_log += std::clamp(pad_zoom, -1.0, 1.0) * std::log(rates_.zoom_rate) * dt_s;
  }

  aim_ = Clamped({pan, tilt, std::exp(zoom_log)}, range_);

  const uint32_t space = input.key_presses[static_cast<size_t>(Key::kSpace)];
  if (space_known_ && space != last_space_presses_) aim_ = Clamped({0.0, 0.0, 1.0}, range_);
  space_known_ = true;
  last_space_presses_ = space;
  return aim_;
}

}  // namespace haptel::station
