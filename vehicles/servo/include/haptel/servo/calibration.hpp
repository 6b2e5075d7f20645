#pragma once
/// @file A channel's calibration: a command in [-1, 1] to a pulse width and
/// back. Piecewise linear about the neutral, so each side of the travel has
/// its own span (an elevator trimmed off-centre, a power channel whose
/// neutral is its minimum).
#include <array>

#include "haptel/config/servo.hpp"
#include "haptel/core/camera_aim.hpp"

namespace haptel::servo {

/// The pulse for `value` in [-1, 1] (clamped; NaN gives neutral_us): v >= 0
/// → neutral_us + v·(max_us − neutral_us); v < 0 → neutral_us + v·(neutral_us
/// − min_us); `reversed` negates v first. The power channel uses [0, 1] and
/// has its neutral at its min, so a negative value is neutral.
double PulseFromCommand(const ServoChannelConfig& channel, double value);

/// The exact inverse of PulseFromCommand, µs to [-1, 1] (clamped; NaN gives
/// 0). A side of zero span (neutral_us == min_us) maps to 0.
double CommandFromPulse(const ServoChannelConfig& channel, double pulse_us);

/// PulseFromCommand for every channel, in BlimpChannel order.
std::array<double, kBlimpChannels> PulsesFromCommands(
    const ServoControllerConfig& config, const std::array<double, kBlimpChannels>& values);

/// Every channel's neutral_us, in BlimpChannel order.
std::array<double, kBlimpChannels> NeutralPulses(const ServoControllerConfig& config);

/// A camera axis's command in [-1, 1]: its value in `aim` over the axis's
/// range (min → -1, max → +1; an empty range → 0).
double CameraAxisCommand(const CameraServoChannel& axis, const CameraAim& aim);
/// The inverse: `aim`'s value on the axis from its command in [-1, 1].
void SetCameraAxis(const CameraServoChannel& axis, double command, CameraAim* aim);

}  // namespace haptel::servo
