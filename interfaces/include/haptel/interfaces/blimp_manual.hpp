#pragma once
/// @file The blimp flown by keys or a game controller (BlimpManualConfig says
/// which, and how): for a person without a haptic device.
///
/// No hands and no forces: Update keeps both force fields disabled in the
/// HAL, so the servo loop renders nothing. The camera follows the head
/// (InputState::head_pan/head_tilt, mouse-look in the window).
#include <cstdint>

#include "haptel/config/blimp_manual.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/blimp_interface.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/key_level.hpp"

namespace haptel::interfaces {

class BlimpManualInterface final : public BlimpInterface {
 public:
  /// Presses and controller disconnects counted in `at_start` (the input as
  /// the interface starts) are not acted on. Validates `config` first
  /// (BlimpManualConfig::ValidateOrThrow: ConfigFieldError).
  BlimpManualInterface(const BlimpManualConfig& config, const InputState& at_start);

  std::string name() const override { return config_.name; }
  BlimpManualInput input_kind() const { return config_.input(); }

  /// Reads one InputState at time `t_s` (s, non-decreasing) and returns the
  /// command. Allocation-free. Neutral (camera aside) while no controller is
  /// connected, and for good once the one there was went away (lost()).
  BlimpCommand Step(double t_s, const InputState& input);

  /// Step, with both force fields disabled in `hal` (stamped now: the servo
  /// loop sees a live interface that renders no force).
  BlimpCommand Update(double t_s, const InputState& input, haptics::Hal& hal);
  /// The catalogue's Update: the person's input in `reading`.
  BlimpCommand Update(double t_s, const BlimpReading& reading, haptics::Hal& hal) override {
    return Update(t_s, reading.person, hal);
  }
  /// No hands: keys and controllers.
  HandTargets HandTargetsFor(const BlimpCommand& /*command*/) const override { return {}; }
  /// Starts again from rest, the input up to `now` seen.
  void Rebase(const InputState& now) override { *this = BlimpManualInterface(config_, now); }

  /// The game controller went away since the interface started.
  bool lost() const override { return lost_; }
  /// A game controller's, while none is connected (as of the last Step):
  /// kNoControllerNotice (gamepad.hpp).
  const char* Notice() const override;
  const char* Help(bool switchable) const override;

 private:
  BlimpCommand Keys(double t_s, const InputState& input);
  BlimpCommand Pad(const InputState& input);

  BlimpManualConfig config_;
  KeyLevel power_;      ///< W/S
  KeyLevel helix_;      ///< ↑/↓
  KeyLevel elevator_;   ///< Page Up/Down
  double swing_ = 0.0;  ///< rudder (or tail rotor at zero power), −1..1: A/D or ←/→
  double last_t_s_ = 0.0;
  bool started_ = false;
  uint32_t seen_stop_ = 0;
  uint32_t disconnects_at_start_ = 0;
  bool lost_ = false;
  bool pad_connected_ = false;  ///< as of the last Step
};

}  // namespace haptel::interfaces
