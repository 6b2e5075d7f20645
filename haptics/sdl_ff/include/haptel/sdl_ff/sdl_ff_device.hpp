#pragma once
/// @file The `sdl-ff` device: a force-feedback joystick or wheel (or a game
/// controller with rumble) that SDL opens, as the device's two hands
/// (docs/haptics.md).
///
/// Its own I/O thread owns every SDL call: it reads the axes and buttons at
/// `poll_hz` (SDL_JoystickUpdate, then SDL_JoystickGetAxis/GetButton: the
/// joystick API locks itself, so the view's thread pumping events at the
/// same time is safe, and the device needs no event loop of its own) and
/// plays the effects at `effect_hz` through SDL's haptic API (ff_model.hpp).
/// SDL's subsystems are reference-counted: the device inits and quits only
/// its own (joystick, haptic), and no global event state is changed. The
/// servo threads only read and write seqlocks and atomics: the hands' poses
/// (ReadWrist answers kNoData between two polls, so the loop's velocity is
/// not a staircase), the written forces and the set-point's field.
///
/// Unplugged (SDL_JoystickGetAttached false): ReadWrist answers kLost from
/// then on (the servo loop zeroes the forces, the session ends the run), and
/// the thread says so once in the log. A device that plays nothing (no
/// haptic and no rumble) is refused: it is not a force-feedback device.
#include <memory>
#include <string>

#include "haptel/config/device.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

class SdlFfDevice final : public Device {
 public:
  static constexpr const char* kDriver = "sdl-ff";

  /// Opens the joystick `config.sdl_ff.joystick` names and starts its
  /// thread. ConfigError naming the file and key when there is no such
  /// joystick, it has no force feedback or rumble, or an axis or button the
  /// file names is not on it.
  explicit SdlFfDevice(const DeviceConfig& config);
  ~SdlFfDevice() override;
  SdlFfDevice(const SdlFfDevice&) = delete;
  SdlFfDevice& operator=(const SdlFfDevice&) = delete;

  const DeviceDescription& description() const override { return description_; }
  DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) override;
  DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) override;
  DeviceStatus WriteWristForce(Side side, const Vec3d& command) override;
  DeviceStatus WriteFingerForces(Side side, const std::array<double, kFingers>& command) override;
  HandPresence Presence(Side side) override;
  void SetpointHint(Side side, const ForceSetpoint& setpoint) override;
  DeviceUseReport UseReport() const override;
  /// "joystick 'NAME' was unplugged" once it was; "" until then.
  std::string UnpluggedLine() const override;

  /// SDL's name of the joystick opened, and what it plays.
  const std::string& joystick_name() const;
  bool plays_effects() const;  ///< SDL's haptic API: spring, constant or sine
  bool rumbles() const;        ///< rumble only (a game controller)

 private:
  struct Io;
  DeviceDescription description_;
  std::unique_ptr<Io> io_;
  std::array<uint64_t, kSides> seen_{};  ///< per side: the newest poll ReadWrist answered
};

/// "" when a joystick the file would open is there (DeviceDriver::available),
/// else a line saying what is missing.
std::string SdlFfUnavailable(const DeviceConfig& config);

}  // namespace haptel::haptics
