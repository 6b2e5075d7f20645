#pragma once
/// @file The blimp's servo controller (the `servo:` section of a blimp
/// vehicle file): which USB servo controller drives the seven channels, on
/// which serial port, and each channel's calibration from a command in
/// [-1, 1] to a pulse width. Read by haptel_servo (haptel/servo/*.hpp).
#include <array>
#include <string>
#include <vector>

#include "haptel/config/archive.hpp"

namespace haptel {

/// The blimp's channels, in this order everywhere (thesis ch. 8.2.1).
enum class BlimpChannel { kElevator, kRudder, kPower, kHelix, kTailRotor, kCameraPan, kCameraTilt };
constexpr int kBlimpChannels = 7;

/// "elevator", "rudder", "power", "helix", "tail_rotor", "camera_pan",
/// "camera_tilt": as written in a file (the keys under `channels:`).
const char* BlimpChannelName(BlimpChannel c);

/// The controller's wire protocol: a Pololu Maestro (compact protocol) or
/// Tom's RC SC-8000.
enum class ServoProtocol { kMaestro, kSc8000 };
/// "maestro", "sc8000", as written in a file.
const char* ServoProtocolName(ServoProtocol protocol);
/// The protocol a name means; false when none does.
bool ParseServoProtocol(const std::string& name, ServoProtocol* protocol);

/// Pulse widths any channel may be calibrated to, µs (hobby servos).
constexpr double kServoMinPulse_us = 500.0;
constexpr double kServoMaxPulse_us = 2500.0;
/// The Maestro's outputs: 0..23 (the 24-channel Mini Maestro; smaller
/// models simply lack the upper ones).
constexpr int kMaestroChannels = 24;
/// The SC-8000's outputs, 0..7, and its pulse range, µs.
constexpr int kSc8000Channels = 8;
constexpr double kSc8000MinPulse_us = 800.0;
constexpr double kSc8000MaxPulse_us = 2200.0;
/// The SC-8000's one serial rate.
constexpr int kSc8000Baud = 9600;

/// One channel's output number and calibration. A command v in [-1, 1]
/// maps to neutral_us + v·(max_us − neutral_us) for v >= 0 and to
/// neutral_us + v·(neutral_us − min_us) below (haptel/servo/calibration.hpp);
/// `power` uses [0, 1] with its neutral at its min.
struct ServoChannelConfig {
  int channel = 0;             ///< the controller's output number (maestro 0..23, sc8000 0..7)
  double min_us = 1000.0;      ///< pulse at command −1
  double neutral_us = 1500.0;  ///< pulse at command 0, and the controller's home position
  double max_us = 2000.0;      ///< pulse at command +1
  bool reversed = false;       ///< the command is negated before the mapping

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(channel),
             config::Required{"the controller's output number (a whole number)"},
             Range{0, kMaestroChannels - 1});
    a->Visit(HAPTEL_NVP(min_us), Range{kServoMinPulse_us, kServoMaxPulse_us});
    a->Visit(HAPTEL_NVP(neutral_us), Range{kServoMinPulse_us, kServoMaxPulse_us});
    a->Visit(HAPTEL_NVP(max_us), Range{kServoMinPulse_us, kServoMaxPulse_us});
    a->Visit(HAPTEL_NVP(reversed));
  }

  /// Throws ConfigFieldError: min_us < max_us, min_us <= neutral_us <=
  /// max_us, every pulse in [500, 2500] µs, channel in [0, 23] (the
  /// controller's config narrows these for the SC-8000).
  void ValidateOrThrow() const;
};

/// A servo output beyond the seven: one axis of a camera the blimp carries
/// (the vehicle file's cameras[i].pan_servo, tilt_servo, zoom_servo; not in
/// the `servo:` section: VehicleConfig::ServoWithCameras collects them).
/// The axis's range maps onto the channel's command -1..1.
struct CameraServoChannel {
  enum class Axis { kPan, kTilt, kZoom };
  ServoChannelConfig output;
  int camera = 0;  ///< its camera's index in VehicleConfig::Cameras()
  Axis axis = Axis::kPan;
  double min = 0.0;  ///< the axis's value at command -1 (rad; a zoom's 1)
  double max = 0.0;  ///< at command +1 (rad; the zoom's zoom_max)
};
/// The most camera axes one controller drives beyond the seven channels.
constexpr int kMaxCameraServoChannels = 12;

struct ServoControllerConfig {
  ServoProtocol protocol = ServoProtocol::kMaestro;
  /// Serial device path, e.g. /dev/ttyACM0 (may be empty in a file: given by --serial-port).
  std::string port;
  /// Maestro: one of 1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200
  /// (ignored by its USB virtual port, used on its TTL pins); SC-8000: 9600.
  int baud = 115200;
  /// Maestro: a CRC-7 byte after each command (the device's "Enable CRC"
  /// setting must match). The SC-8000 has none: false.
  bool crc = false;
  /// s: the controller's own serial timeout (set the same value in the
  /// Maestro's settings): after this long without a valid command it sends
  /// every channel to its home (neutral_us) position.
  double controller_timeout_s = 0.5;
  /// s: Maestro: how often the adapter asks Get Errors.
  double error_poll_s = 0.5;
  /// Per BlimpChannel, in its order.
  std::array<ServoChannelConfig, kBlimpChannels> channels;
  /// The cameras' axes on further outputs (not in the file; at most
  /// kMaxCameraServoChannels, their outputs checked by the vehicle file).
  std::vector<CameraServoChannel> camera_channels;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(protocol),
             config::Choice<ServoProtocol>{
                 {{ServoProtocol::kMaestro, "maestro"}, {ServoProtocol::kSc8000, "sc8000"}}});
    a->Visit(HAPTEL_NVP(port));
    // A file naming the SC-8000 need not give its only rate.
    if constexpr (Archive::kReads) {
      if (protocol == ServoProtocol::kSc8000) baud = kSc8000Baud;
    }
    a->Visit(HAPTEL_NVP(baud));
    a->Visit(HAPTEL_NVP(crc));
    a->Visit(HAPTEL_NVP(controller_timeout_s), config::Range{0.02, 60.0});
    a->Visit(HAPTEL_NVP(error_poll_s), config::Range{0.01, 60.0});
    a->Group(
        "channels",
        [this](auto* each) {
          for (size_t i = 0; i < channels.size(); ++i) {
            const char* name = BlimpChannelName(static_cast<BlimpChannel>(i));
            each->Visit(
                config::MakeNameValue(name, &channels[i]),
                config::Required{std::string("the ") + name +
                                 " channel (a mapping: channel, min_us, neutral_us, max_us, "
                                 "reversed)"});
          }
        },
        config::Required{"a mapping of the seven channels (elevator, rudder, power, helix, "
                         "tail_rotor, camera_pan, camera_tilt)"});
  }

  /// Throws ConfigFieldError naming the first field out of range. A
  /// channel's errors are prefixed "channels.<name>." (e.g.
  /// "channels.rudder.min_us"); output numbers must be distinct; the
  /// SC-8000 needs outputs 0..7, pulses within 800..2200 µs, baud 9600 and
  /// no CRC; the Maestro outputs 0..23.
  void ValidateOrThrow() const;
};

}  // namespace haptel
