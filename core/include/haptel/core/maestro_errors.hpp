#pragma once
/// @file The Pololu Maestro's error register (Maestro user's guide, section
/// 4.e "Errors"): its bits and their names. A plain value shared by the
/// blimp's servo adapter that reads it (Get Errors), the link that carries
/// it (BlimpState.controller_errors) and the operator's side that shows it.
///
/// The device sets a bit when the error happens, and clears the whole
/// register when Get Errors reads it. On every error it sends each servo to
/// its home position (its "On startup or error" setting): a set bit means
/// the blimp did not fly what it was told at least once since the last read.
#include <cstdint>
#include <string>

namespace haptel::maestro_errors {

/// The error register's bits.
enum ErrorBit : uint16_t {
  /// A byte's stop bit was not where expected: a baud rate that differs
  /// from the device's, or noise on the line.
  kSerialSignalError = 1U << 0,
  /// The UART's own buffer overflowed (should not happen in normal use).
  kSerialOverrunError = 1U << 1,
  /// The firmware's receive buffer was full: a byte was lost.
  kSerialRxBufferFull = 1U << 2,
  /// A command's CRC-7 byte did not match (CRC mode): the command was ignored.
  kSerialCrcError = 1U << 3,
  /// A malformed command: an unknown command byte, a command cut by the next.
  kSerialProtocolError = 1U << 4,
  /// No valid command within the device's serial timeout.
  kSerialTimeout = 1U << 5,
  /// A script on the device overflowed its stack, call stack or program
  /// counter (Haptel runs no script on it).
  kScriptStackError = 1U << 6,
  kScriptCallStackError = 1U << 7,
  kScriptProgramCounterError = 1U << 8,
};

/// The bits the device defines (0..8).
constexpr uint16_t kDefinedBits = 0x01FF;

/// "serial signal error", "serial overrun", "serial RX buffer full", "CRC
/// error", "protocol error", "serial timeout", "script stack error", "script
/// call stack error", "script program counter error" for bit 0..8; "bit N"
/// for 9..15; "?" beyond.
const char* ErrorBitName(int bit);

/// The set bits' names, highest bit first, comma-separated:
/// "serial timeout, CRC error"; "none" for 0.
std::string ErrorNames(uint16_t errors);

/// The names and the raw register, as the operator reads them:
/// "CRC error, serial timeout (register 0x0028)"; "none" for 0.
std::string ErrorsText(uint16_t errors);

}  // namespace haptel::maestro_errors
