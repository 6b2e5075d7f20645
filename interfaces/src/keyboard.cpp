#include "haptel/interfaces/keyboard.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptel/config/error.hpp"

namespace haptel::interfaces {

KeyboardInterface::KeyboardInterface(const KeyboardConfig& config, const InputBox& input,
                                     int speed_levels)
    : config_(Validated(config)), input_(input), levels_(speed_levels) {
  if (speed_levels < 1) throw std::invalid_argument("KeyboardInterface: speed_levels must be >= 1");
  // Presses made before this interface existed (e.g. under the previous
  // interface of the run) belong to that one.
  const InputState s = input_.Load();
  throttle_.seen_plus = s.presses_up;
  throttle_.seen_minus = s.presses_down;
  steering_.seen_plus = s.presses_left;
  steering_.seen_minus = s.presses_right;
  seen_stop_ = s.presses_stop;
}

void KeyboardInterface::StepAxis(Axis& axis, double t_s, bool plus_held, bool minus_held,
                                 uint32_t plus_presses, uint32_t minus_presses) const {
  // Unsigned differences: correct across counter wrap-around.
  const uint32_t new_plus = plus_presses - axis.seen_plus;
  const uint32_t new_minus = minus_presses - axis.seen_minus;
  axis.seen_plus = plus_presses;
  axis.seen_minus = minus_presses;
  const auto clamp = [this](long v) {
    return static_cast<int>(std::clamp<long>(v, -levels_, levels_));
  };
  axis.level =
      clamp(static_cast<long>(axis.level) + static_cast<long>(std::min<uint32_t>(new_plus, 1000)) -
            static_cast<long>(std::min<uint32_t>(new_minus, 1000)));

  // Both keys held cancel out: no repeat either way.
  const int held = plus_held == minus_held ? 0 : (plus_held ? 1 : -1);
  if (new_plus + new_minus > 0 || held != axis.held) {
    // A fresh press (or a change of direction) restarts the typematic clock.
    axis.next_repeat_s = t_s + config_.repeat_s;
  } else if (held != 0 && t_s >= axis.next_repeat_s) {
    // Every repeat period that passed since the last one steps once, so the
    // ramp does not depend on the session rate.
    const double periods = std::floor((t_s - axis.next_repeat_s) / config_.repeat_s) + 1.0;
    const int steps = static_cast<int>(std::min(periods, 2.0 * levels_));
    axis.level = clamp(static_cast<long>(axis.level) + static_cast<long>(held) * steps);
    axis.next_repeat_s += periods * config_.repeat_s;
  }
  axis.held = held;

  // A press seen this tick counts even if already released: it returns to
  // zero on the next tick, not before the command carried it.
  if (config_.release_to_zero && !plus_held && !minus_held && new_plus + new_minus == 0)
    axis.level = 0;
}

MotorCommand KeyboardInterface::Step(double t_s, const InputState& s) {
  StepAxis(throttle_, t_s, s.key_up, s.key_down, s.presses_up, s.presses_down);
  StepAxis(steering_, t_s, s.key_left, s.key_right, s.presses_left, s.presses_right);
  const bool stop_pressed = s.presses_stop != seen_stop_;
  seen_stop_ = s.presses_stop;
  if (stop_pressed || s.key_stop) {
    throttle_.level = 0;
    steering_.level = 0;
  }
  return Command();
}

MotorCommand KeyboardInterface::Command() const {
  const double forward = static_cast<double>(throttle_.level) / levels_;
  const double turn = config_.turn_share * static_cast<double>(steering_.level) / levels_;
  return Mix(forward, turn);
}

MotorCommand KeyboardInterface::Update(double t_s, const VehicleFeedback& /*feedback*/,
                                       haptics::Hal& hal) {
  // No hands: both fields disabled, stamped now, so the servo loop renders
  // no force and sees a live (not stalled) interface.
  hal.SetField(haptics::Side::kLeft, haptics::ForceField{});
  hal.SetField(haptics::Side::kRight, haptics::ForceField{});
  return Step(t_s, input_.Load());
}

HandTargets KeyboardInterface::HandTargetsFor(const DriveIntent& /*intent*/) const { return {}; }

}  // namespace haptel::interfaces
