#pragma once
/// @file The adapter's side of the blimp's servo controller: pulse widths
/// for the seven channels out, the Maestro's error register in.
///
/// A frame the port takes only in part is finished before anything else is
/// written (its tail is kept), so the controller never sees a command cut
/// in two; while that tail still cannot go, new frames are skipped and
/// counted. Nothing here allocates after construction. Everything that
/// touches the port throws SerialLost when the port has gone away.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "haptel/config/servo.hpp"
#include "haptel/servo/serial_port.hpp"

namespace haptel::servo {

struct ServoOutputCounters {
  uint64_t frames_sent = 0;  ///< whole frames handed to the port (Send, GoHome, Get Errors)
  uint64_t bytes_sent = 0;
  uint64_t write_short = 0;       ///< writes the port took only in part (the rest follows later)
  uint64_t frames_skipped = 0;    ///< frames not written: the previous one's tail was still waiting
  uint64_t error_replies = 0;     ///< Get Errors replies read (Maestro)
  uint64_t replies_missing = 0;   ///< polls whose reply had not come by the next poll (Maestro)
  uint64_t unexpected_bytes = 0;  ///< bytes read that answer no request (dropped)
};

class ServoOutput {
 public:
  /// Validates `config` (throws ConfigFieldError) and takes the port.
  ServoOutput(const ServoControllerConfig& config, std::unique_ptr<ByteStream> port);

  /// Writes the seven channels' pulses (BlimpChannel order, µs; each
  /// clamped to its channel's [min_us, max_us], NaN to neutral_us): seven
  /// Maestro Set Target commands (with CRC when configured) in one write,
  /// or one SC-8000 frame.
  void Send(const std::array<double, kBlimpChannels>& pulse_us);

  /// Reads what the controller sent. Maestro: asks Get Errors at the first
  /// call and every error_poll_s after (`now_s`: any monotonic clock, s),
  /// and reads the 2-byte replies; bytes that fit no outstanding request
  /// are counted and dropped (resynchronising; a pair whose high byte has
  /// bits no error uses is shifted by one byte). SC-8000: every byte read is
  /// unexpected.
  void Update(double now_s);

  /// Every channel to its home position: Maestro Go Home (0xA2); SC-8000 a
  /// frame with every channel at neutral_us.
  void GoHome();

  /// The Maestro's error register as the last Get Errors reply gave it
  /// (the device clears it on reading, so 0 until something new goes wrong).
  uint16_t last_errors() const { return last_errors_; }
  /// Every error bit any reply has carried.
  uint16_t errors_seen() const { return errors_seen_; }
  const ServoOutputCounters& counters() const { return counters_; }
  const ServoControllerConfig& config() const { return config_; }

 private:
  /// Writes the waiting tail; true when nothing waits any more.
  bool Flush();
  /// Writes one frame (after the waiting tail); false when it was skipped.
  bool WriteFrame(const uint8_t* data, size_t size);
  void ReadReplies();

  ServoControllerConfig config_;
  std::unique_ptr<ByteStream> port_;
  ServoOutputCounters counters_;
  static constexpr size_t kFrameBytes = 64;
  std::array<uint8_t, kFrameBytes> frame_{};
  std::array<uint8_t, kFrameBytes> pending_{};
  size_t pending_size_ = 0;
  size_t pending_sent_ = 0;
  bool polled_ = false;
  double next_poll_s_ = 0.0;
  int outstanding_ = 0;  ///< Get Errors requests not yet answered (0 or 1)
  std::array<uint8_t, 2> reply_{};
  size_t reply_size_ = 0;
  uint16_t last_errors_ = 0;
  uint16_t errors_seen_ = 0;
};

}  // namespace haptel::servo
