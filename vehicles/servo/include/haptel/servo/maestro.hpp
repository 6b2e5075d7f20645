#pragma once
/// @file The Pololu Maestro's compact serial protocol (Maestro user's
/// guide, section 5.e), as pure byte functions that allocate nothing.
///
/// A command is a command byte (bit 7 set) then data bytes (bit 7 clear);
/// targets and positions are in quarter-µs, sent as two 7-bit halves. With
/// the device's "Enable CRC" setting on, each command is followed by its
/// CRC-7 byte. Replies (Get Errors, Get Position) are two bytes, low byte
/// first, and carry no CRC.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "haptel/core/maestro_errors.hpp"

namespace haptel::servo::maestro {

constexpr uint8_t kSetTarget = 0x84;           ///< channel, target low 7 bits, target high 7 bits
constexpr uint8_t kSetMultipleTargets = 0x9F;  ///< count, first channel, count × (low, high)
constexpr uint8_t kGetPosition = 0x90;         ///< channel → 2-byte position
constexpr uint8_t kGetErrors = 0xA1;           ///< → 2-byte error register (then cleared)
constexpr uint8_t kGoHome = 0xA2;              ///< every channel to its home position

constexpr int kChannels = 24;            ///< outputs 0..23 (Mini Maestro 24)
constexpr uint16_t kMaxTarget = 0x3FFF;  ///< 14 bits of quarter-µs
constexpr size_t kReplyBytes = 2;

/// The error register's bits (Get Errors) and their names: shared with the
/// link and the operator's side (haptel/core/maestro_errors.hpp).
using namespace ::haptel::maestro_errors;

/// The longest command: Set Multiple Targets for all 24 outputs, and its CRC.
constexpr size_t kMaxPacketBytes = 3 + 2 * kChannels + 1;

/// One command's bytes (and its CRC byte when asked for).
struct Packet {
  std::array<uint8_t, kMaxPacketBytes> bytes{};
  size_t size = 0;
  const uint8_t* data() const { return bytes.data(); }
};

/// CRC-7 as the Maestro computes it (polynomial 0x91, reflected): for each
/// byte, crc ^= byte, then 8 times: if (crc & 1) crc ^= 0x91; crc >>= 1.
/// The result is in 0..0x7F. Crc7({0x83, 0x01}) == 0x17.
uint8_t Crc7(const uint8_t* data, size_t size);

/// A pulse width in quarter-µs, rounded, clamped to [0, kMaxTarget]
/// (NaN gives 0, which the Maestro reads as "stop pulses": callers clamp first).
uint16_t QuarterUs(double pulse_us);

/// Set Target: 0x84, channel, target & 0x7F, (target >> 7) & 0x7F.
/// 1500 µs (6000) on channel 2 is 84 02 70 2E.
Packet SetTarget(int channel, uint16_t target_quarter_us, bool crc);
/// Set Multiple Targets for `count` (1..24) consecutive outputs from
/// `first_channel`.
Packet SetMultipleTargets(int first_channel, const uint16_t* targets_quarter_us, int count,
                          bool crc);
Packet GetErrors(bool crc);
Packet GoHome(bool crc);
Packet GetPosition(int channel, bool crc);

/// A 2-byte reply's value: low | high << 8.
constexpr uint16_t ReplyValue(uint8_t low, uint8_t high) {
  return static_cast<uint16_t>(low | (high << 8));
}

}  // namespace haptel::servo::maestro
