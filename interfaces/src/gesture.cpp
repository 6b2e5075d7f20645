#include "haptel/interfaces/gesture.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "offset_shape.hpp"

namespace haptel::interfaces {

using haptics::Side;
using haptics::Vec3d;

using detail::Shape;
using detail::Unshape;

GestureInterface::GestureInterface(const GestureConfig& config, const VehicleGeometry& vehicle)
    : config_(Validated(config)) {
  if (config_.shared_control.enabled) shared_.emplace(config_.shared_control, vehicle);
  field_.enabled = true;
  field_.neutral = config_.neutral;
  field_.stiffness = config_.field_stiffness;
  field_.stiffness_growth = config_.field_stiffness_growth;
  field_.damping = config_.field_damping;
  field_.wall_stiffness = config_.wall_stiffness;
  // Critically damped-ish for a ~1 kg arm on the wall spring.
  field_.wall_damping = 2.0 * std::sqrt(config_.wall_stiffness * 1.0);
}

TreadCommand GestureInterface::Map(const Vec3d& hand) const {
  const double forward =
      Shape(hand[0] - config_.neutral[0], config_.dead_zone, config_.full_forward);
  const double turn = config_.turn_share *
                      Shape(hand[1] - config_.neutral[1], config_.dead_zone, config_.full_turn);
  return Mix(forward, turn);
}

HandTargets GestureInterface::HandTargetsFor(const MotionIntent& intent) const {
  Vec3d target = config_.neutral;
  target[0] += Unshape(intent.forward, config_.dead_zone, config_.full_forward);
  const double turn_fraction = config_.turn_share > 0 ? intent.turn / config_.turn_share : 0.0;
  target[1] += Unshape(turn_fraction, config_.dead_zone, config_.full_turn);
  HandTargets targets;
  targets[haptics::Index(Side::kRight)] = HandGoal{.position = target};
  return targets;
}

TreadCommand GestureInterface::Update(double t_s, const VehicleFeedback& feedback,
                                      haptics::Hal& hal) {
  const haptics::HandSample hand = hal.LatestSample(Side::kRight);
  if (!hand.valid) {
    hal.ZeroForces();
    return {};
  }
  const bool contact = feedback.bumper_left || feedback.bumper_right;
  if (contact) {
    if (!field_.wall_active) {
      // The wall stands where the hand is, facing the motion that drove the
      // robot in: forward, plus the turn towards the side that touched.
      const double side = feedback.bumper_left == feedback.bumper_right ? 0.0
                          : feedback.bumper_left                        ? 0.5
                                                                        : -0.5;
      const double norm = std::sqrt(1.0 + side * side);
      field_.wall_normal = {1.0 / norm, side / norm, 0.0};
      field_.wall_point = hand.position;
      field_.wall_active = true;
    }
    last_contact_s_ = t_s;
  } else if (field_.wall_active && t_s - last_contact_s_ >= config_.wall_release_s) {
    field_.wall_active = false;
  }
  if (shared_) {
    guidance_ = shared_->Guide(echoes_.Filter(feedback.ranges), hand.position, config_.neutral,
                               [this](const Vec3d& p) { return Map(p); });
    shared_->Apply(guidance_, field_);
  }
  hal.SetField(Side::kRight, field_);
  hal.SetField(Side::kLeft, haptics::ForceField{});
  return Map(hand.position);
}

std::optional<TreadCommand> GestureInterface::CommandNow(double /*t_s*/,
                                                         const haptics::Hal& hal) const {
  const haptics::HandSample hand = hal.LatestSample(Side::kRight);
  return hand.valid ? Map(hand.position) : TreadCommand{};
}

namespace {

// The gesture interfaces in the catalogue (catalog.hpp).
const RegisterInterface<RobotFamily, GestureConfig> kGestureInterfaces{
    {{.name = "gesture",
      .family = VehicleFamily::kRobot,
      .hands = {false, true},
      .input = InterfaceInput::kHands,
      .physics = false,
      .summary = "no controls: the right hand's offset drives the motors, a field pulls it to "
                 "neutral"},
     {.name = "gesture-shared",
      .family = VehicleFamily::kRobot,
      .hands = {false, true},
      .input = InterfaceInput::kHands,
      .physics = false,
      .shared_control = true,
      .summary = "gesture with haptic shared control: a bounded push away from commands that "
                 "lead into an obstacle"}},
    LoadGesture,
    [](const GestureConfig& config, const InterfaceParts& parts) {
      return std::make_unique<GestureInterface>(config, parts.vehicle);
    }};

}  // namespace

}  // namespace haptel::interfaces
