#include "haptel/sdl_ff/sdl_effects.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace haptel::haptics::sdl_ff {

namespace {

int16_t Level(double fraction) {
  return static_cast<int16_t>(std::lround(32767.0 * std::clamp(fraction, -1.0, 1.0)));
}

}  // namespace

SDL_HapticEffect SpringEffect(const std::array<SpringAxis, kFfAxes>& axes) {
  SDL_HapticEffect e;
  std::memset(&e, 0, sizeof e);
  e.type = SDL_HAPTIC_SPRING;
  SDL_HapticCondition& c = e.condition;
  c.direction.type = SDL_HAPTIC_CARTESIAN;  // a condition's axes are its own; unused
  c.length = SDL_HAPTIC_INFINITY;
  for (int j = 0; j < kFfAxes; ++j) {
    const SpringAxis& a = axes[static_cast<size_t>(j)];
    if (!a.active) continue;
    c.right_sat[j] = c.left_sat[j] = 0xFFFF;
    c.right_coeff[j] = c.left_coeff[j] = Level(a.coefficient);
    c.center[j] = Level(a.centre);
  }
  return e;
}

SDL_HapticEffect ConstantEffect(const std::array<double, kFfAxes>& levels) {
  SDL_HapticEffect e;
  std::memset(&e, 0, sizeof e);
  e.type = SDL_HAPTIC_CONSTANT;
  SDL_HapticConstant& c = e.constant;
  c.length = SDL_HAPTIC_INFINITY;
  c.direction.type = SDL_HAPTIC_CARTESIAN;
  double norm2 = 0.0;
  for (const double l : levels) norm2 += l * l;
  const double norm = std::sqrt(norm2);
  for (int j = 0; j < kFfAxes; ++j) {
    // From the opposite side, scaled so the direction keeps its precision.
    c.direction.dir[j] =
        norm > 0.0
            ? static_cast<Sint32>(std::lround(-10000.0 * levels[static_cast<size_t>(j)] / norm))
            : 0;
  }
  if (norm == 0.0) c.direction.dir[0] = 1;  // any direction: the level is 0
  c.level = Level(std::min(norm, 1.0));
  return e;
}

SDL_HapticEffect ShakeEffect(const SdlFfDeviceConfig& config) {
  SDL_HapticEffect e;
  std::memset(&e, 0, sizeof e);
  e.type = SDL_HAPTIC_SINE;
  SDL_HapticPeriodic& p = e.periodic;
  p.direction.type = SDL_HAPTIC_CARTESIAN;
  p.direction.dir[0] = 1;
  p.period = static_cast<Uint16>(std::clamp(std::lround(1000.0 / config.shake_hz), 1L, 65535L));
  p.magnitude = Level(config.shake_level);
  p.length = static_cast<Uint32>(std::lround(1000.0 * config.shake_s));
  return e;
}

uint16_t RumbleLevel(double fraction) {
  return static_cast<uint16_t>(std::lround(65535.0 * std::clamp(fraction, 0.0, 1.0)));
}

}  // namespace haptel::haptics::sdl_ff
