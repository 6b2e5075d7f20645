#pragma once
/// @file What the `sdl-ff` device computes without SDL, as pure functions
/// (tested without hardware): the hands from the axes, the deadman, and the
/// force-feedback effects for the forces the servo loop writes.
///
/// Axes are SDL's, normalised to [−1, 1] (AxisFromSdl). A hand's position is
/// linear in its axes (SdlFfAxisMap) or on a rim (SdlFfRimMap); its lever
/// on axis j, ∂position/∂a_j, turns a force at the hand into the force along
/// that axis: the generalised force F·∂p/∂a_j over |∂p/∂a_j|, in newtons at
/// the hand, so that the device's full effect level is the device's force
/// limit at the hand whatever the axis' span.
///
/// Effects (PlanEffects), per force-feedback axis j (SDL's haptic axis j is
/// taken to be joystick axis j: X and Y on a stick, the wheel on a wheel):
/// - the interface's centring field (ForceField stiffness k, neutral n) as
///   the device's spring on each axis a hand coordinate moves linearly:
///   centre where that coordinate is at n, coefficient k·|∂p/∂a| over the
///   force limit (the spring's force at unit deflection), clamped to 1;
/// - what the spring does not render — the wall, the field's damping and
///   growth, the proxy coupling, a cue — as one constant force: the written
///   force minus the spring's model of itself, along each axis;
/// - a contact of the vehicle (ShakeTrigger: the set-point's contact count
///   grew) starts a sine shake;
/// - on a device with rumble only: the shake and a wall pressed (its force
///   over the limit) as rumble.
#include <array>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics::sdl_ff {

constexpr int kMaxAxes = 16;  ///< axes read (a wheel with pedals has 3–6)
constexpr int kFfAxes = 3;    ///< SDL's haptic directions have at most 3 axes

/// Normalised axis values, [−1, 1]; axes the device lacks read 0.
using Axes = std::array<double, kMaxAxes>;

/// SDL's axis value (−32768..32767) → [−1, 1].
double AxisFromSdl(int16_t raw);
/// The coordinate's deflection: [−1, 1] for a stick, [0, 1] from a pedal's
/// rest (low or high), less the reverse axis' [0, 1].
double Deflection(const SdlFfAxisMap& map, const Axes& axes);

struct HandPose {
  Vec3d position{};                               ///< m, device frame
  std::array<double, 4> orientation{1, 0, 0, 0};  ///< (w, x, y, z)
};
HandPose HandFromAxes(const SdlFfHandMap& hand, const Axes& axes);
/// ∂position/∂a_axis at `axes`, m per unit of axis value.
Vec3d HandLever(const SdlFfHandMap& hand, const Axes& axes, int axis);
/// The deadman's button (bit b of `buttons`) down, or its axis pressed past the threshold.
bool DeadmanHeld(const SdlFfDeadman& deadman, const Axes& axes, uint64_t buttons);
/// The glove's sensors (radians: the device calibrates itself) of a hand closed
/// on a grip (the four fingers' joints at `flexion`) or open.
std::array<double, kGloveJoints> GlovePosture(const std::array<double, 3>& flexion, bool closed);

/// What the servo thread last gave one hand, as the effects see it.
struct FfSide {
  bool used = false;      ///< the device has this side
  bool fresh = false;     ///< the set-point and force are recent (else: no force)
  ForceField field;       ///< the tick's set-point's field (Device::SetpointHint)
  Vec3d force{};          ///< N, the wrist force last written
  uint64_t contacts = 0;  ///< the set-point's count of the vehicle's contacts
};

struct SpringAxis {
  bool active = false;
  double centre = 0.0;       ///< axis value, [−1, 1]
  double coefficient = 0.0;  ///< of the full level per unit of deflection, [0, 1]
};

struct FfPlan {
  std::array<SpringAxis, kFfAxes> spring{};
  /// Per axis, of the full level, [−1, 1]; + pushes the axis' value up.
  std::array<double, kFfAxes> constant{};
  /// How hard a hand presses into an active wall: its force over the limit, [0, 1].
  double wall_press = 0.0;
};

/// The effects for the hands at `axes`. `ff_axes`: the device's
/// force-feedback axes (≤ kFfAxes); `spring`: whether it plays springs (else
/// the spring's share goes into the constant force); `force_limit`: N at
/// the full level (> 0).
FfPlan PlanEffects(const SdlFfDeviceConfig& config, const std::array<FfSide, kSides>& sides,
                   const Axes& axes, int ff_axes, bool spring, double force_limit);

/// Decides when a contact starts a shake, once per effect period.
class ShakeTrigger {
 public:
  explicit ShakeTrigger(const SdlFfDeviceConfig& config) : shake_s_(config.shake_s) {}
  /// True when a shake starts at `t_s`: a side's count of the vehicle's
  /// contacts grew since the last call, while no shake plays. Forces never
  /// start one (a driven control's coupling steps its force all the time).
  bool Step(double t_s, const std::array<FfSide, kSides>& sides);

 private:
  double shake_s_;
  uint64_t contacts_ = 0;
  double until_s_ = -1e9;
};

}  // namespace haptel::haptics::sdl_ff
