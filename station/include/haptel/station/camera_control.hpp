#pragma once
/// @file How a person in the control room steers a camera (thesis 8.2.1:
/// the surveillance camera's pan, tilt and zoom): from what the view's
/// window and a game controller report (interfaces::InputState, the
/// window's pointer) to where the camera is to point (CameraAim), kept
/// within what its head and lens allow. Pure: no SDL, no clock; the
/// station steps it at its own rate.
///
/// - Dragging the picture with the left button held drags the scene: what
///   was under the pointer stays under it (a pixel is the field of view
///   over the window's width, so a zoomed-in picture moves slower).
/// - The wheel zooms: each notch away from the person by kWheelZoomStep.
/// - Arrows (and W/A/S/D) pan and tilt at key_rate fields of view a
///   second; Page Up / Page Down zoom in and out by zoom_rate a second.
/// - A game controller's left stick pans and tilts (at stick_rate fields
///   of view a second, full over), its right trigger zooms in, its left
///   trigger out, its right stick's y too (up: in).
/// - Space points the camera straight ahead at its widest.
#include <cstdint>

#include "haptel/core/camera_aim.hpp"
#include "haptel/haptics/pointer.hpp"
#include "haptel/interfaces/input.hpp"

namespace haptel::station {

struct CameraControlRates {
  double key_rate = 0.5;    ///< fields of view a second, a key held
  double stick_rate = 1.0;  ///< fields of view a second, a stick full over
  double zoom_rate = 2.0;   ///< zoom factor a second, a key or trigger full on
  double dead_zone = 0.15;  ///< of a stick's or trigger's travel: ignored
};

class CameraControl {
 public:
  /// Each wheel notch zooms by this factor.
  static constexpr double kWheelZoomStep = 1.25;

  /// Steers a camera whose widest horizontal field of view is
  /// `widest_fov_deg`, within `range`, from `start` (clamped).
  CameraControl(const CameraRange& range, double widest_fov_deg, const CameraAim& start,
                const CameraControlRates& rates = {});

  /// The camera's range and widest field of view learnt (the vehicle's
  /// status says them): the aim is kept within the new range.
  void SetCamera(const CameraRange& range, double widest_fov_deg);
  /// Points the camera at `aim` (clamped), as a command line's --aim does.
  void Set(const CameraAim& aim);

  /// One step of `dt_s` with the person's input now: returns the aim.
  const CameraAim& Step(const interfaces::InputState& input, const haptics::PointerState& pointer,
                        double dt_s);

  const CameraAim& aim() const { return aim_; }
  const CameraRange& range() const { return range_; }
  /// The field of view at the current zoom, rad.
  double FovRad() const;

 private:
  CameraRange range_;
  double widest_fov_deg_;
  CameraControlRates rates_;
  CameraAim aim_;
  // What the last step saw, for differences (drag, wheel, presses).
  bool dragging_ = false;
  int last_x_ = 0;
  int last_y_ = 0;
  bool wheel_known_ = false;
  int64_t last_wheel_ = 0;
  bool space_known_ = false;
  uint32_t last_space_presses_ = 0;
};

}  // namespace haptel::station
