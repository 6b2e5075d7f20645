#pragma once
/// @file The `sdl-ff` device's effects as SDL's haptic API takes them
/// (ff_model.hpp computes them), pure so they are tested without a device.
///
/// SDL's directions say where a force comes *from* (SDL_HapticDirection);
/// its Cartesian axes are the joystick's (x right, y towards the user), so a
/// force that pushes axis j's value up comes from −j. Levels are SDL's
/// 16-bit ones: 32767 is the device's full force.
#include <SDL2/SDL_haptic.h>

#include <array>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/sdl_ff/ff_model.hpp"

namespace haptel::haptics::sdl_ff {

/// The spring (SDL_HAPTIC_SPRING, endless): per axis its centre and its
/// coefficient on both sides, saturating at the full level; an inactive
/// axis has none.
SDL_HapticEffect SpringEffect(const std::array<SpringAxis, kFfAxes>& axes);
/// The constant force (SDL_HAPTIC_CONSTANT, endless): level |levels|
/// (clamped to full), from the direction opposite to `levels`.
SDL_HapticEffect ConstantEffect(const std::array<double, kFfAxes>& levels);
/// The contact's shake (SDL_HAPTIC_SINE on the first axis): shake_hz,
/// shake_level of full, for shake_s.
SDL_HapticEffect ShakeEffect(const SdlFfDeviceConfig& config);
/// A fraction of full ([0, 1], clamped) as a rumble motor's 16-bit speed.
uint16_t RumbleLevel(double fraction);

}  // namespace haptel::haptics::sdl_ff
