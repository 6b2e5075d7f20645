#pragma once
/// @file The keyboard interface: the thesis's practice-lap remote control
/// (ch. 8.1.2), a PC whose keyboard works the steering and the throttle.
///
/// Throttle and steering are integer levels in −L..+L (L: the vehicle's
/// drive.speed_levels). Each press of up/down steps the throttle one level,
/// each press of left/right the steering (left is +: turn > 0 turns left).
/// Presses are read from InputState's counters, so a press shorter than a
/// session tick still steps, and the command of that tick carries it. A held
/// key steps again every `repeat_s`. With `release_to_zero`, a pair of keys
/// both released returns its level to 0 (the session's next tick); space
/// sets both levels to 0 at once and holds them there while held.
///
/// No hands and no forces: HandTargetsFor is empty, and Update keeps both
/// force fields disabled in the HAL.
#include <cstdint>

#include "haptel/config/keyboard.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/interfaces/key_level.hpp"

namespace haptel::interfaces {

class KeyboardInterface final : public MediatorInterface {
 public:
  /// Keeps a reference to `input` (it must outlive the interface). Presses
  /// counted before construction are not replayed. Throws
  /// std::invalid_argument when speed_levels < 1, ConfigFieldError (one) for a
  /// `config` KeyboardConfig::ValidateOrThrow refuses.
  KeyboardInterface(const KeyboardConfig& config, const InputBox& input, int speed_levels);

  std::string name() const override { return config_.name; }
  TreadCommand Update(double t_s, const VehicleFeedback& feedback, haptics::Hal& hal) override;
  /// Presses so far are seen; throttle and steering back to level 0.
  void Rebase(const InputState& now) override;
  HandTargets HandTargetsFor(const MotionIntent& intent) const override;
  bool NeedsPhysics() const override { return false; }
  const char* Help(bool switchable) const override {
    return switchable ? "arrows or W/A/S/D drive, space stops, F1-F6 switch, Esc ends"
                      : "arrows or W/A/S/D drive, space stops, Esc ends";
  }

  /// Reads one InputState at time `t_s` (s, non-decreasing) and returns the
  /// command: what Update does, without the HAL.
  TreadCommand Step(double t_s, const InputState& input);

  int throttle_level() const { return throttle_.level(); }
  int steering_level() const { return steering_.level(); }
  int speed_levels() const { return levels_; }

 private:
  TreadCommand Command() const;

  KeyboardConfig config_;
  const InputBox& input_;
  int levels_;
  KeyLevel throttle_;  ///< up/down (or W/S)
  KeyLevel steering_;  ///< left/right (or A/D)
  uint32_t seen_stop_ = 0;
};

}  // namespace haptel::interfaces
