#include "haptel/servo/servo_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "haptel/config/error.hpp"
#include "haptel/servo/calibration.hpp"
#include "haptel/servo/maestro.hpp"
#include "haptel/servo/sc8000.hpp"

namespace haptel::servo {
namespace {

double Clamped(const ServoChannelConfig& c, double pulse_us) {
  return std::isnan(pulse_us) ? c.neutral_us : std::clamp(pulse_us, c.min_us, c.max_us);
}

/// Bits of the error register no Maestro error uses.
constexpr uint8_t kUnusedHighBits = 0xFE;

}  // namespace

ServoOutput::ServoOutput(const ServoControllerConfig& config, std::unique_ptr<ByteStream> port)
    : config_(Validated(config)), port_(std::move(port)) {
  if (port_ == nullptr) throw SerialUnavailable("servo output: no port");
  if (config_.camera_channels.size() > camera_pulse_us_.size()) {
    throw ConfigError("servo output: " + std::to_string(config_.camera_channels.size()) +
                      " camera servo channels; expected at most " +
                      std::to_string(camera_pulse_us_.size()));
  }
  for (size_t i = 0; i < config_.camera_channels.size(); ++i)
    camera_pulse_us_[i] = config_.camera_channels[i].output.neutral_us;
}

void ServoOutput::SetCameraPulse(size_t index, double pulse_us) {
  if (index < config_.camera_channels.size()) camera_pulse_us_[index] = pulse_us;
}

bool ServoOutput::Flush() {
  if (pending_sent_ >= pending_size_) return true;
  const size_t left = pending_size_ - pending_sent_;
  const size_t n = port_->Write(pending_.data() + pending_sent_, left);
  counters_.bytes_sent += n;
  pending_sent_ += n;
  if (n < left) {
    ++counters_.write_short;
    return false;
  }
  pending_size_ = pending_sent_ = 0;
  return true;
}

bool ServoOutput::WriteFrame(const uint8_t* data, size_t size) {
  if (!Flush()) {
    ++counters_.frames_skipped;
    return false;
  }
  const size_t n = port_->Write(data, size);
  counters_.bytes_sent += n;
  ++counters_.frames_sent;
  if (n < size) {
    ++counters_.write_short;
    std::memcpy(pending_.data(), data + n, size - n);
    pending_size_ = size - n;
    pending_sent_ = 0;
  }
  return true;
}

void ServoOutput::Send(const std::array<double, kBlimpChannels>& pulse_us) {
  if (config_.protocol == ServoProtocol::kMaestro) {
    size_t size = 0;
    for (size_t i = 0; i < pulse_us.size(); ++i) {
      const ServoChannelConfig& c = config_.channels[i];
      const maestro::Packet p =
          maestro::SetTarget(c.channel, maestro::QuarterUs(Clamped(c, pulse_us[i])), config_.crc);
      std::memcpy(frame_.data() + size, p.data(), p.size);
      size += p.size;
    }
    for (size_t i = 0; i < config_.camera_channels.size(); ++i) {
      const ServoChannelConfig& c = config_.camera_channels[i].output;
      const maestro::Packet p = maestro::SetTarget(
          c.channel, maestro::QuarterUs(Clamped(c, camera_pulse_us_[i])), config_.crc);
      std::memcpy(frame_.data() + size, p.data(), p.size);
      size += p.size;
    }
    WriteFrame(frame_.data(), size);
    return;
  }
  uint8_t mask = 0;
  std::array<uint16_t, sc8000::kChannels> values{};
  for (size_t i = 0; i < pulse_us.size(); ++i) {
    const ServoChannelConfig& c = config_.channels[i];
    mask = static_cast<uint8_t>(mask | (1U << c.channel));
    values[static_cast<size_t>(c.channel)] = sc8000::TenthUs(Clamped(c, pulse_us[i]));
  }
  for (size_t i = 0; i < config_.camera_channels.size(); ++i) {
    const ServoChannelConfig& c = config_.camera_channels[i].output;
    if (c.channel < 0 || c.channel >= sc8000::kChannels) continue;  // refused by the vehicle file
    mask = static_cast<uint8_t>(mask | (1U << c.channel));
    values[static_cast<size_t>(c.channel)] = sc8000::TenthUs(Clamped(c, camera_pulse_us_[i]));
  }
  const sc8000::Frame f = sc8000::MakeFrame(mask, values);
  WriteFrame(f.data(), f.size);
}

void ServoOutput::GoHome() {
  if (config_.protocol == ServoProtocol::kMaestro) {
    const maestro::Packet p = maestro::GoHome(config_.crc);
    WriteFrame(p.data(), p.size);
    return;
  }
  for (size_t i = 0; i < config_.camera_channels.size(); ++i)
    camera_pulse_us_[i] = config_.camera_channels[i].output.neutral_us;
  Send(NeutralPulses(config_));
}

void ServoOutput::ReadReplies() {
  std::array<uint8_t, 64> buffer{};
  // Bounded: a port that never stops talking cannot hold the loop.
  for (int reads = 0; reads < 64; ++reads) {
    const size_t n = port_->Read(buffer.data(), buffer.size());
    if (n == 0) return;
    for (size_t i = 0; i < n; ++i) {
      if (config_.protocol != ServoProtocol::kMaestro || outstanding_ == 0) {
        ++counters_.unexpected_bytes;
        continue;
      }
      reply_[reply_size_++] = buffer[i];
      if (reply_size_ < reply_.size()) continue;
      if ((reply_[1] & kUnusedHighBits) != 0) {
        // Not an error register: out of step by a byte. Drop the first.
        ++counters_.unexpected_bytes;
        reply_[0] = reply_[1];
        reply_size_ = 1;
        continue;
      }
      last_errors_ = maestro::ReplyValue(reply_[0], reply_[1]);
      errors_seen_ = static_cast<uint16_t>(errors_seen_ | last_errors_);
      window_errors_ = static_cast<uint16_t>(window_errors_ | last_errors_);
      ++counters_.error_replies;
      --outstanding_;
      reply_size_ = 0;
    }
  }
}

void ServoOutput::JudgeWindow(double now_s) {
  const bool unanswered = outstanding_ > 0 || poll_unsent_;
  const uint64_t unexpected = counters_.unexpected_bytes - window_unexpected_from_;
  if (!unanswered && window_errors_ == 0 && unexpected == 0) {
    wrong_in_a_row_ = 0;
    return;
  }
  ++counters_.polls_wrong;
  if (wrong_in_a_row_ == 0) {
    wrong_since_s_ = window_opened_s_;
    wrong_errors_ = 0;
    wrong_unanswered_ = 0;
    wrong_unexpected_ = 0;
  }
  ++wrong_in_a_row_;
  wrong_errors_ = static_cast<uint16_t>(wrong_errors_ | window_errors_);
  wrong_unanswered_ += unanswered ? 1 : 0;
  wrong_unexpected_ += unexpected;
  if (untrusted_ || wrong_in_a_row_ < kUntrustedAfterPolls) return;
  untrusted_ = true;
  // Once: the one allocation after construction.
  char span[96];
  std::snprintf(span, sizeof span,
                "%d error polls in a row went wrong (over %.1f s): ", wrong_in_a_row_,
                now_s - wrong_since_s_);
  std::string why;
  const auto add = [&why](const std::string& part) { why += (why.empty() ? "" : "; ") + part; };
  if (wrong_unexpected_ > 0) {
    add(std::to_string(wrong_unexpected_) +
        " bytes that answer no request (a Maestro speaks only when asked: another device on the "
        "port, a wrong "
        "baud rate, or noise on the line)");
  }
  if (wrong_unanswered_ > 0) {
    add(std::to_string(wrong_unanswered_) +
        " of them got no reply (does the controller answer on this port: powered, its serial mode, "
        "its baud rate?)");
  }
  if (wrong_errors_ != 0) add("replies carried " + maestro_errors::ErrorsText(wrong_errors_));
  untrusted_reason_ = "servo controller on " + port_->name() + " cannot be trusted: " + span + why;
}

void ServoOutput::Update(double now_s) {
  ReadReplies();
  if (config_.protocol != ServoProtocol::kMaestro) return;
  if (polled_ && now_s < next_poll_s_) return;
  if (polled_) JudgeWindow(now_s);
  polled_ = true;
  next_poll_s_ = now_s + config_.error_poll_s;
  if (outstanding_ > 0) {
    // The last poll went unanswered (lost on the line, or the command was
    // dropped): forget it and whatever part of its reply came.
    counters_.replies_missing += static_cast<uint64_t>(outstanding_);
    counters_.unexpected_bytes += reply_size_;
    outstanding_ = 0;
    reply_size_ = 0;
  }
  // The next window opens.
  window_opened_s_ = now_s;
  window_errors_ = 0;
  window_unexpected_from_ = counters_.unexpected_bytes;
  const maestro::Packet p = maestro::GetErrors(config_.crc);
  poll_unsent_ = !WriteFrame(p.data(), p.size);
  if (!poll_unsent_) ++outstanding_;
}

}  // namespace haptel::servo
