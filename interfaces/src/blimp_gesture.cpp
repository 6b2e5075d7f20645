#include "haptel/interfaces/blimp_gesture.hpp"

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "offset_shape.hpp"

namespace haptel::interfaces {

using detail::Shape;
using detail::Unshape;
using haptics::Side;
using haptics::Vec3d;

BlimpGestureInterface::BlimpGestureInterface(const BlimpGestureConfig& config)
    : config_(Validated(config)) {
  for (Side side : {Side::kLeft, Side::kRight}) {
    haptics::ForceField& f = fields_[haptics::Index(side)];
    f.enabled = true;
    f.neutral = side == Side::kLeft ? config_.left_neutral : config_.right_neutral;
    f.stiffness = config_.field_stiffness;
    f.stiffness_growth = config_.field_stiffness_growth;
    f.damping = config_.field_damping;
  }
}

BlimpCommand BlimpGestureInterface::Map(const Vec3d& left, const Vec3d& right,
                                        const HeadDirection& head) const {
  const BlimpGestureConfig& c = config_;
  BlimpCommand out;
  // Right hand: a stick. Forward pushes the nose down.
  out.elevator = -Shape(right[0] - c.right_neutral[0], c.dead_zone, c.full_elevator);
  out.rudder = Shape(right[1] - c.right_neutral[1], c.dead_zone, c.full_rudder);
  // Left hand: power forward only; the helix plane up/down.
  out.power = std::max(0.0, Shape(left[0] - c.left_neutral[0], c.dead_zone, c.full_power));
  out.helix = Shape(left[2] - c.left_neutral[2], c.dead_zone, c.full_helix);
  // With no power, sideways is the tail rotor (the quick turnabout).
  if (out.power == 0.0)
    out.tail_rotor = Shape(left[1] - c.left_neutral[1], c.dead_zone, c.full_tail);
  out.camera_pan = head.pan;
  out.camera_tilt = head.tilt;
  return Clamped(out);
}

HandTargets BlimpGestureInterface::HandTargetsFor(const BlimpCommand& command) const {
  const BlimpGestureConfig& c = config_;
  const BlimpCommand k = Clamped(command);
  Vec3d right = c.right_neutral;
  right[0] += Unshape(-k.elevator, c.dead_zone, c.full_elevator);
  right[1] += Unshape(k.rudder, c.dead_zone, c.full_rudder);
  Vec3d left = c.left_neutral;
  left[0] += Unshape(k.power, c.dead_zone, c.full_power);
  left[2] += Unshape(k.helix, c.dead_zone, c.full_helix);
  if (k.power == 0.0) left[1] += Unshape(k.tail_rotor, c.dead_zone, c.full_tail);
  HandTargets targets;
  targets[haptics::Index(Side::kRight)] = HandGoal{.position = right};
  targets[haptics::Index(Side::kLeft)] = HandGoal{.position = left};
  return targets;
}

BlimpCommand BlimpGestureInterface::Update(double /*t_s*/, const BlimpReading& reading,
                                           haptics::Hal& hal) {
  return Update(reading.head, hal, reading.now_ns);
}

BlimpCommand BlimpGestureInterface::Update(const HeadDirection& head, haptics::Hal& hal) {
  return Update(head, hal, MonotonicNs());
}

BlimpCommand BlimpGestureInterface::Update(const HeadDirection& head, haptics::Hal& hal,
                                           int64_t now_ns) {
  const haptics::HandSample left = hal.LatestSample(Side::kLeft);
  const haptics::HandSample right = hal.LatestSample(Side::kRight);
  if (!left.valid || !right.valid) {
    hal.ZeroForces();
    BlimpCommand neutral;
    neutral.camera_pan = head.pan;
    neutral.camera_tilt = head.tilt;
    return Clamped(neutral);
  }
  hal.SetField(Side::kLeft, fields_[haptics::Index(Side::kLeft)], now_ns);
  hal.SetField(Side::kRight, fields_[haptics::Index(Side::kRight)], now_ns);
  return Map(left.position, right.position, head);
}

namespace {

// The blimp's gesture cockpit in the catalogue (catalog.hpp).
const RegisterInterface<BlimpFamily, BlimpGestureConfig> kBlimpGestureInterface{
    {{.name = "blimp-gesture",
      .family = VehicleFamily::kBlimp,
      .hands = {true, true},
      .input = InterfaceInput::kHands,
      .physics = false,
      .summary = "the blimp's gesture cockpit: the right hand steers, the left gives power"}},
    LoadBlimpGesture,
    [](const BlimpGestureConfig& config, const InterfaceParts&) {
      return std::make_unique<BlimpGestureInterface>(config);
    }};

}  // namespace

}  // namespace haptel::interfaces
