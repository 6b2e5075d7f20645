#pragma once
/// @file A Pololu Maestro that misbehaves on purpose, played by a test on a
/// line's device end (a pty's master): it decodes Set Target (with or
/// without CRC) into its outputs, as the device would, and answers Get
/// Errors as its manner says — a healthy device, one that reports a CRC
/// error at every poll, one that never answers, one that answers with
/// random bytes, or a healthy one with a single CRC error. The simulated
/// controller (sim_servo_controller.hpp) is the faithful device; this one
/// is a fault's.
#include <array>
#include <cstdint>
#include <memory>
#include <random>

#include "haptel/servo/maestro.hpp"
#include "haptel/servo/serial_port.hpp"

namespace haptel::test {

class FakeMaestro {
 public:
  enum class Manner {
    kHealthy,            ///< every poll answered 0: no error
    kCrcErrorEveryPoll,  ///< every poll answered "CRC error"
    kSilent,             ///< reads everything, answers nothing
    kRandomBytes,        ///< answers each poll with kNoiseBytes random bytes instead
    kOneCrcError,        ///< healthy, but the poll number kOneErrorAt reports a CRC error
  };
  static constexpr int kNoiseBytes = 24;
  static constexpr int kOneErrorAt = 2;  ///< the third poll (0-based)

  FakeMaestro(std::unique_ptr<servo::ByteStream> line, bool crc, Manner manner)
      : line_(std::move(line)), crc_(crc), manner_(manner) {
    outputs_us_.fill(0.0);
  }

  /// Reads every waiting byte, obeys and answers.
  void Update() {
    std::array<uint8_t, 256> buffer{};
    for (;;) {
      const size_t n = line_->Read(buffer.data(), buffer.size());
      if (n == 0) return;
      bytes_read_ += n;
      for (size_t i = 0; i < n; ++i) Feed(buffer[i]);
    }
  }

  /// From now on, answers as `manner` says (a device that starts failing).
  void set_manner(Manner manner) { manner_ = manner; }

  int polls() const { return polls_; }
  uint64_t bytes_read() const { return bytes_read_; }
  uint64_t bytes_written() const { return bytes_written_; }
  /// What the adapter should have read of them as replies to its polls.
  int replies_sent() const { return replies_sent_; }
  /// An output's pulse as the last Set Target for it said, µs (0: none yet).
  double output_us(int output) const { return outputs_us_[static_cast<size_t>(output)]; }

 private:
  void Feed(uint8_t byte) {
    if ((byte & 0x80) != 0) {
      packet_[0] = byte;
      size_ = 1;
      const size_t data = byte == servo::maestro::kSetTarget ? 3 : 0;
      need_ = 1 + data + (crc_ ? 1 : 0);
    } else if (need_ != 0 && size_ < packet_.size()) {
      packet_[size_++] = byte;
    }
    if (need_ == 0 || size_ < need_) return;
    need_ = 0;
    if (packet_[0] == servo::maestro::kSetTarget && packet_[1] < outputs_us_.size()) {
      outputs_us_[packet_[1]] = static_cast<double>(packet_[2] | (packet_[3] << 7)) / 4.0;
    } else if (packet_[0] == servo::maestro::kGetErrors) {
      Answer(polls_++);
    }
  }

  void Answer(int poll) {
    switch (manner_) {
      case Manner::kHealthy:
        return Reply(0);
      case Manner::kCrcErrorEveryPoll:
        return Reply(servo::maestro::kSerialCrcError);
      case Manner::kSilent:
        return;
      case Manner::kRandomBytes: {
        std::array<uint8_t, kNoiseBytes> noise{};
        for (uint8_t& b : noise) b = static_cast<uint8_t>(rng_());
        bytes_written_ += line_->Write(noise.data(), noise.size());
        return;
      }
      case Manner::kOneCrcError:
        return Reply(poll == kOneErrorAt ? servo::maestro::kSerialCrcError : 0);
    }
  }

  void Reply(uint16_t value) {
    const std::array<uint8_t, 2> bytes = {static_cast<uint8_t>(value & 0xFF),
                                          static_cast<uint8_t>(value >> 8)};
    bytes_written_ += line_->Write(bytes.data(), bytes.size());
    ++replies_sent_;
  }

  std::unique_ptr<servo::ByteStream> line_;
  bool crc_;
  Manner manner_;
  std::mt19937 rng_{26};
  std::array<uint8_t, 8> packet_{};
  size_t size_ = 0;
  size_t need_ = 0;
  int polls_ = 0;
  int replies_sent_ = 0;
  uint64_t bytes_read_ = 0;
  uint64_t bytes_written_ = 0;
  std::array<double, servo::maestro::kChannels> outputs_us_{};
};

}  // namespace haptel::test
