#pragma once
/// @file The gamepad interface: a game controller's sticks and triggers.
///
/// forward = −(left stick y) + right trigger − left trigger, clamped to
/// [-1, 1] (SDL's stick y is + down); turn = −(left or right stick x)
/// × turn_share (SDL's x is + right; turn > 0 turns left). Sticks have a
/// radial dead zone, rescaled so the output grows continuously from 0 at
/// its edge to 1 at full deflection. Nothing drives unless the deadman
/// button is held (as teleop_twist_joy's enable_button) and a controller is
/// connected. A controller disconnected during the run makes lost() true for
/// good: the session stops the vehicle and ends the run as aborted.
///
/// No hands and no forces: HandTargetsFor is empty, and Update keeps both
/// force fields disabled in the HAL.
#include <array>
#include <cstdint>

#include "haptel/config/gamepad.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::interfaces {

/// Radial dead zone on a stick: inside it 0; outside, the radius is mapped
/// from [dz, 1] to [0, 1] along the same direction, so there is no step at
/// the edge and full deflection is still 1. NaN reads as 0.
std::array<double, 2> RadialDeadZone(double x, double y, double dz);
/// A trigger's pull past its dead zone, rescaled to [0, 1].
double TriggerDeadZone(double t, double dz);

/// What the person reads on screen and in the log while no game controller
/// is connected.
inline constexpr const char* kNoControllerNotice =
    "no game controller connected: plug one in (Esc ends the run)";

class GamepadInterface final : public MediatorInterface {
 public:
  /// Keeps a reference to `input` (it must outlive the interface).
  /// Disconnects counted before construction do not count as lost. Validates
  /// `config` first (GamepadConfig::ValidateOrThrow: ConfigFieldError).
  GamepadInterface(const GamepadConfig& config, const InputBox& input);

  std::string name() const override { return config_.name; }
  TreadCommand Update(double t_s, const VehicleFeedback& feedback, haptics::Hal& hal) override;
  HandTargets HandTargetsFor(const MotionIntent& intent) const override;
  bool NeedsPhysics() const override { return false; }

  /// Pure mapping of one InputState (what Update does, without the HAL and
  /// the box). Zero when not connected, deadman released, or lost.
  MotionIntent Intent(const InputState& input) const;
  TreadCommand Map(const InputState& input) const;

  /// A controller went away since construction (pad_disconnects grew).
  bool lost() const override;

  /// While no controller is connected (none was found at the start, or it
  /// has not been opened yet): kNoControllerNotice.
  const char* Notice() const override;

 private:
  GamepadConfig config_;
  const InputBox& input_;
  uint32_t disconnects_at_start_ = 0;
};

}  // namespace haptel::interfaces
