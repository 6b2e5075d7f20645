#pragma once
/// @file The adapter's side of the blimp's servo controller: pulse widths
/// for the seven channels out, the Maestro's error register in.
///
/// A frame the port takes only in part is finished before anything else is
/// written (its tail is kept), so the controller never sees a command cut
/// in two; while that tail still cannot go, new frames are skipped and
/// counted. Nothing here allocates after construction (but once, the
/// message when the controller is judged untrustworthy). Everything that
/// touches the port throws SerialLost when the port has gone away.
///
/// When a Maestro cannot be trusted. Each error poll opens a window that the
/// next poll closes; the window went wrong when
///   - the reply to its poll carried any error bit: the device sends every
///     servo home on every error (Maestro guide 4.e), so the blimp did not fly
///     what it was told at least once in the window. Line errors (serial
///     signal, overrun, RX buffer full, CRC, protocol) mean commands arrived
///     garbled or not at all; a serial timeout means none arrived for the
///     device's timeout although we send at 50 Hz; script errors mean the
///     device runs a script we did not give it;
///   - its poll got no whole reply (or could not be written): a controller
///     that does not answer may not be hearing the commands either;
///   - bytes came that answer no request: a Maestro speaks only when asked,
///     so these are another device on the port, a wrong baud rate, or noise
///     that may as well corrupt what we send.
/// One or two windows going wrong are shown (last_errors, errors_seen, the
/// counters; the state carries the register) and tolerated: one burst of
/// noise can spoil at most two windows (a garbled reply in one, the command
/// it also garbled reported by the next). So
/// kUntrustedAfterPolls = 3 windows in a row going wrong (1.5 s at the
/// shipped error_poll_s of 0.5 s) make the controller untrusted, for good:
/// untrusted() and untrusted_reason(), which names the errors, the missing
/// replies and the stray bytes of those windows. The adapter then holds the
/// blimp at neutral and reports a fault, and the run ends as vehicle lost.
/// The SC-8000 answers nothing and is not judged.
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
  uint64_t polls_wrong = 0;  ///< poll windows that went wrong (an error bit, no reply, stray bytes)
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
  /// The cameras' outputs (ServoControllerConfig::camera_channels, in its
  /// order, µs; clamped as above), sent in the same command or frame as the
  /// seven channels from the next Send on. Out of range `index`: ignored.
  void SetCameraPulse(size_t index, double pulse_us);
  /// What SetCameraPulse last set (the neutral before).
  double camera_pulse_us(size_t index) const {
    return index < camera_pulse_us_.size() ? camera_pulse_us_[index] : 0.0;
  }

  /// Reads what the controller sent. Maestro: asks Get Errors at the first
  /// call and every error_poll_s after (`now_s`: any monotonic clock, s),
  /// and reads the 2-byte replies; bytes that fit no outstanding request
  /// are counted and dropped (resynchronising; a pair whose high byte has
  /// bits no error uses is shifted by one byte); each poll first judges the
  /// window the previous one opened (untrusted()). SC-8000: every byte read
  /// is unexpected.
  void Update(double now_s);

  /// Every channel to its home position: Maestro Go Home (0xA2); SC-8000 a
  /// frame with every channel at neutral_us.
  void GoHome();

  /// The Maestro's error register as the last Get Errors reply gave it
  /// (the device clears it on reading, so 0 until something new goes wrong).
  uint16_t last_errors() const { return last_errors_; }
  /// Every error bit any reply has carried.
  uint16_t errors_seen() const { return errors_seen_; }
  /// Whether the controller has been judged untrustworthy (see the file's
  /// comment): kUntrustedAfterPolls poll windows in a row went wrong.
  bool untrusted() const { return untrusted_; }
  /// Why, once untrusted: "servo controller on /dev/ttyACM0 cannot be
  /// trusted: 3 error polls in a row went wrong (over 1.5 s): replies carried
  /// CRC error (register 0x0008)"; empty while trusted.
  const std::string& untrusted_reason() const { return untrusted_reason_; }
  /// Poll windows in a row that went wrong, up to now.
  int polls_wrong_in_a_row() const { return wrong_in_a_row_; }

  /// Poll windows in a row that make a Maestro untrusted (see the file's comment).
  static constexpr int kUntrustedAfterPolls = 3;
  const ServoOutputCounters& counters() const { return counters_; }
  const ServoControllerConfig& config() const { return config_; }

 private:
  /// Writes the waiting tail; true when nothing waits any more.
  bool Flush();
  /// Writes one frame (after the waiting tail); false when it was skipped.
  bool WriteFrame(const uint8_t* data, size_t size);
  void ReadReplies();
  /// Judges the poll window that ends at `now_s` (the next poll is due).
  void JudgeWindow(double now_s);

  ServoControllerConfig config_;
  std::unique_ptr<ByteStream> port_;
  ServoOutputCounters counters_;
  std::array<double, kMaxCameraServoChannels> camera_pulse_us_{};
  static constexpr size_t kFrameBytes = 128;
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
  // The poll window under way, and the run of windows that went wrong.
  bool poll_unsent_ = false;             ///< the window's poll could not be written
  uint16_t window_errors_ = 0;           ///< error bits of the replies in this window
  uint64_t window_unexpected_from_ = 0;  ///< counters_.unexpected_bytes when it opened
  int wrong_in_a_row_ = 0;
  double wrong_since_s_ = 0.0;     ///< when the first window of the run opened
  uint16_t wrong_errors_ = 0;      ///< error bits over the run
  int wrong_unanswered_ = 0;       ///< polls without a reply over the run
  uint64_t wrong_unexpected_ = 0;  ///< stray bytes over the run
  double window_opened_s_ = 0.0;
  bool untrusted_ = false;
  std::string untrusted_reason_;
};

}  // namespace haptel::servo
