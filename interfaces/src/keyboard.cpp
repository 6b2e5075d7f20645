#include "haptel/interfaces/keyboard.hpp"

#include <algorithm>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/catalog.hpp"

namespace haptel::interfaces {

KeyboardInterface::KeyboardInterface(const KeyboardConfig& config, const InputBox& input,
                                     int speed_levels)
    : config_(Validated(config)),
      input_(input),
      levels_(speed_levels),
      throttle_(-std::max(speed_levels, 1), std::max(speed_levels, 1), config_.repeat_s,
                config_.release_to_zero),
      steering_(-std::max(speed_levels, 1), std::max(speed_levels, 1), config_.repeat_s,
                config_.release_to_zero) {
  if (speed_levels < 1) throw std::invalid_argument("KeyboardInterface: speed_levels must be >= 1");
  // Presses made before this interface existed (e.g. under the previous
  // interface of the run) belong to that one.
  const InputState s = input_.Load();
  throttle_.Skip(s.presses_up, s.presses_down);
  steering_.Skip(s.presses_left, s.presses_right);
  seen_stop_ = s.presses_stop;
}

void KeyboardInterface::Rebase(const InputState& now) {
  throttle_.Skip(now.presses_up, now.presses_down);
  steering_.Skip(now.presses_left, now.presses_right);
  seen_stop_ = now.presses_stop;
  throttle_.set_level(0);
  steering_.set_level(0);
}

TreadCommand KeyboardInterface::Step(double t_s, const InputState& s) {
  throttle_.Step(t_s, s.key_up, s.key_down, s.presses_up, s.presses_down);
  steering_.Step(t_s, s.key_left, s.key_right, s.presses_left, s.presses_right);
  const bool stop_pressed = s.presses_stop != seen_stop_;
  seen_stop_ = s.presses_stop;
  if (stop_pressed || s.key_stop) {
    throttle_.set_level(0);
    steering_.set_level(0);
  }
  return Command();
}

TreadCommand KeyboardInterface::Command() const {
  const double forward = static_cast<double>(throttle_.level()) / levels_;
  const double turn = config_.turn_share * static_cast<double>(steering_.level()) / levels_;
  return Mix(forward, turn);
}

TreadCommand KeyboardInterface::Update(double t_s, const VehicleFeedback& /*feedback*/,
                                       haptics::Hal& hal) {
  // No hands: both fields disabled, stamped now, so the servo loop renders
  // no force and sees a live (not stalled) interface.
  hal.SetField(haptics::Side::kLeft, haptics::ForceField{});
  hal.SetField(haptics::Side::kRight, haptics::ForceField{});
  return Step(t_s, input_.Load());
}

HandTargets KeyboardInterface::HandTargetsFor(const MotionIntent& /*intent*/) const { return {}; }

namespace {

// The keyboard in the catalogue (catalog.hpp).
const RegisterInterface<RobotFamily, KeyboardConfig> kKeyboardInterface{
    {{.name = "keyboard",
      .family = VehicleFamily::kRobot,
      .hands = {false, false},
      .input = InterfaceInput::kKeys,
      .physics = false,
      .summary = "a person's arrow keys (or W/A/S/D)"}},
    LoadKeyboard,
    [](const KeyboardConfig& config, const InterfaceParts& parts) {
      return std::make_unique<KeyboardInterface>(config, PersonsInput(config.name, parts),
                                                 parts.speed_levels);
    }};

}  // namespace

}  // namespace haptel::interfaces
