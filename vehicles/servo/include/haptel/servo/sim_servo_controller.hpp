#pragma once
/// @file A simulated servo controller: the device's end of the serial line
/// (a pty's master end in the simulated blimp and the tests). It decodes
/// the bytes as the device would and holds each output's pulse width.
///
/// Maestro (compact protocol): Set Target, Set Multiple Targets, Get
/// Errors (replies with the error register, then clears it), Go Home, Get
/// Position (replies with the output's target: speed and acceleration
/// limits are not simulated, outputs jump to their targets). With CRC on, a
/// command whose CRC byte is wrong is dropped and sets the CRC error bit; a
/// byte with bit 7 set where data was expected, an unknown command byte or
/// an output number out of range sets the protocol error bit, and decoding
/// resumes at the next command byte; data bytes outside a command are
/// ignored and counted. As on the device, every error sends every output to
/// its home position (the channel's neutral_us; 1500 µs for outputs no
/// channel uses). Targets are clamped to the channel's [min_us, max_us],
/// as the Maestro's own Min/Max settings (set them to the calibration) do;
/// outputs no channel uses to [500, 2500] µs.
///
/// SC-8000: frames are found by their 7E 7E; a frame with a bad IO
/// character or a value outside 8000..22000 (a truncated frame runs into
/// the next one's 7E 7E) is dropped and counted, and the search resumes
/// one byte after its start; bytes outside frames are counted.
///
/// Timeout: after controller_timeout_s without a valid command every output
/// goes home (and, on the Maestro, the serial timeout bit is set). The real
/// SC-8000 has no such timeout — it holds its last pulses forever; our
/// simulation of it times out all the same, and on the real one the
/// vehicle node's command watchdog is the only failsafe.
///
/// Bytes count as arriving when Update reads them. Update allocates nothing.
#include <array>
#include <cstdint>
#include <memory>

#include "haptel/config/servo.hpp"
#include "haptel/servo/maestro.hpp"
#include "haptel/servo/sc8000.hpp"
#include "haptel/servo/serial_port.hpp"

namespace haptel::servo {

struct SimServoCounters {
  uint64_t commands = 0;          ///< valid commands (Maestro) or frames (SC-8000) obeyed
  uint64_t malformed_bytes = 0;   ///< bytes outside any command or frame, or unknown command bytes
  uint64_t crc_errors = 0;        ///< Maestro commands dropped for a wrong CRC byte
  uint64_t frames_dropped = 0;    ///< commands or frames begun and dropped (any reason)
  uint64_t timeouts = 0;          ///< times the controller timed out
  uint64_t reply_bytes_lost = 0;  ///< reply bytes the line did not take
};

class SimServoController {
 public:
  /// Validates `config` (throws ConfigFieldError) and takes the device's
  /// end of the line. Every output starts at its home position.
  SimServoController(const ServoControllerConfig& config, std::unique_ptr<ByteStream> line);

  /// Reads and decodes every waiting byte, answers requests, and applies
  /// the timeout at `now_s` (any monotonic clock, s; the first call starts it).
  void Update(double now_s);

  /// The seven channels' pulses (BlimpChannel order, µs), from their outputs.
  const std::array<double, kBlimpChannels>& pulse_us() const { return pulse_us_; }
  /// Any output's pulse, by the controller's output number (µs).
  double output_pulse_us(int output) const;
  /// Whether the controller timed out and no valid command has come since.
  bool timed_out() const { return timed_out_; }
  /// The Maestro's error register (as Get Errors would read it).
  uint16_t errors() const { return errors_; }
  const SimServoCounters& counters() const { return counters_; }

 private:
  void FeedMaestro(uint8_t byte, double now_s);
  void ExecuteMaestro(double now_s);
  void DecodeSc8000(double now_s);
  void Valid(double now_s);
  void Error(uint16_t bit);
  void HomeAll();
  void SetOutput(int output, double pulse_us);
  void Reply(uint16_t value);

  ServoControllerConfig config_;
  std::unique_ptr<ByteStream> line_;
  SimServoCounters counters_;
  int outputs_ = maestro::kChannels;
  std::array<double, maestro::kChannels> output_us_{};
  std::array<double, maestro::kChannels> home_us_{};
  std::array<double, maestro::kChannels> min_us_{};
  std::array<double, maestro::kChannels> max_us_{};
  std::array<double, kBlimpChannels> pulse_us_{};
  uint16_t errors_ = 0;
  bool started_ = false;
  bool timed_out_ = false;
  double last_valid_s_ = 0.0;
  // Maestro: the command being received.
  std::array<uint8_t, maestro::kMaxPacketBytes> packet_{};
  size_t packet_size_ = 0;
  size_t packet_need_ = 0;  ///< its full size (with CRC); 0: no command under way
  // SC-8000: bytes not yet decoded.
  std::array<uint8_t, 512> pending_{};
  size_t pending_size_ = 0;
};

}  // namespace haptel::servo
