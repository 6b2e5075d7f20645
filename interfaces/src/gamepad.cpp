#include "haptel/interfaces/gamepad.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/catalog.hpp"

namespace haptel::interfaces {

namespace {

double Axis(const InputState& s, PadAxis a) { return s.pad_axes[static_cast<int>(a)]; }
bool Button(const InputState& s, PadButton b) { return s.pad_buttons[static_cast<int>(b)]; }

bool DeadmanHeld(const InputState& s, GamepadDeadman d) {
  switch (d) {
    case GamepadDeadman::kNone:
      return true;
    case GamepadDeadman::kA:
      return Button(s, PadButton::kA);
    case GamepadDeadman::kB:
      return Button(s, PadButton::kB);
    case GamepadDeadman::kX:
      return Button(s, PadButton::kX);
    case GamepadDeadman::kY:
      return Button(s, PadButton::kY);
    case GamepadDeadman::kLeftShoulder:
      return Button(s, PadButton::kLeftShoulder);
    case GamepadDeadman::kRightShoulder:
      return Button(s, PadButton::kRightShoulder);
  }
  return false;
}

}  // namespace

std::array<double, 2> RadialDeadZone(double x, double y, double dz) {
  const double r = std::hypot(x, y);
  if (!(r > dz)) return {0.0, 0.0};  // also catches NaN
  const double scaled = std::min(1.0, (r - dz) / (1.0 - dz));
  return {x / r * scaled, y / r * scaled};
}

double TriggerDeadZone(double t, double dz) {
  if (!(t > dz)) return 0.0;
  return std::min(1.0, (t - dz) / (1.0 - dz));
}

GamepadInterface::GamepadInterface(const GamepadConfig& config, const InputBox& input)
    : config_(Validated(config)),
      input_(input),
      disconnects_at_start_(input.Load().pad_disconnects) {}

bool GamepadInterface::lost() const {
  return input_.Load().pad_disconnects != disconnects_at_start_;
}

const char* GamepadInterface::Notice() const {
  return input_.Load().pad_connected ? nullptr : kNoControllerNotice;
}

MotionIntent GamepadInterface::Intent(const InputState& s) const {
  if (!s.pad_connected || s.pad_disconnects != disconnects_at_start_) return {};
  if (!DeadmanHeld(s, config_.deadman)) return {};
  const auto left =
      RadialDeadZone(Axis(s, PadAxis::kLeftX), Axis(s, PadAxis::kLeftY), config_.dead_zone);
  const double triggers =
      TriggerDeadZone(Axis(s, PadAxis::kTriggerRight), config_.trigger_dead_zone) -
      TriggerDeadZone(Axis(s, PadAxis::kTriggerLeft), config_.trigger_dead_zone);
  MotionIntent intent;
  intent.forward = std::clamp(-left[1] + triggers, -1.0, 1.0);
  double x = left[0];
  if (config_.turn_axis == GamepadTurnAxis::kRightX) {
    x = RadialDeadZone(Axis(s, PadAxis::kRightX), Axis(s, PadAxis::kRightY), config_.dead_zone)[0];
  }
  intent.turn = -x * config_.turn_share;
  return intent;
}

TreadCommand GamepadInterface::Map(const InputState& s) const {
  const MotionIntent intent = Intent(s);
  return Mix(intent.forward, intent.turn);
}

TreadCommand GamepadInterface::Update(double /*t_s*/, const VehicleFeedback& /*feedback*/,
                                      haptics::Hal& hal) {
  // No hands: both fields disabled, stamped now (see KeyboardInterface).
  hal.SetField(haptics::Side::kLeft, haptics::ForceField{});
  hal.SetField(haptics::Side::kRight, haptics::ForceField{});
  return Map(input_.Load());
}

HandTargets GamepadInterface::HandTargetsFor(const MotionIntent& /*intent*/) const { return {}; }

namespace {

// The game controller in the catalogue (catalog.hpp).
const RegisterInterface<RobotFamily, GamepadConfig> kGamepadInterface{
    {{.name = "gamepad",
      .family = VehicleFamily::kRobot,
      .hands = {false, false},
      .input = InterfaceInput::kGamepad,
      .physics = false,
      .summary = "a person's game controller"}},
    LoadGamepad,
    [](const GamepadConfig& config, const InterfaceParts& parts) {
      return std::make_unique<GamepadInterface>(config, PersonsInput(config.name, parts));
    }};

}  // namespace

}  // namespace haptel::interfaces
