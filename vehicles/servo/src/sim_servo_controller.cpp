#include "haptel/servo/sim_servo_controller.hpp"

#include <algorithm>
#include <cstring>
#include <utility>
#include <vector>

#include "haptel/config/error.hpp"

namespace haptel::servo {
namespace {

/// The home of an output no channel uses, µs.
constexpr double kUnusedHome_us = 1500.0;
/// How many reads one Update makes at most (a line that never stops
/// talking cannot hold it).
constexpr int kMaxReads = 256;

}  // namespace

SimServoController::SimServoController(const ServoControllerConfig& config,
                                       std::unique_ptr<ByteStream> line)
    : config_(Validated(config)), line_(std::move(line)) {
  if (line_ == nullptr) throw SerialUnavailable("simulated servo controller: no line");
  const bool sc8000 = config_.protocol == ServoProtocol::kSc8000;
  outputs_ = sc8000 ? sc8000::kChannels : maestro::kChannels;
  for (int o = 0; o < maestro::kChannels; ++o) {
    const auto i = static_cast<size_t>(o);
    home_us_[i] = kUnusedHome_us;
    min_us_[i] = sc8000 ? kSc8000MinPulse_us : kServoMinPulse_us;
    max_us_[i] = sc8000 ? kSc8000MaxPulse_us : kServoMaxPulse_us;
  }
  std::vector<ServoChannelConfig> used(config_.channels.begin(), config_.channels.end());
  for (const CameraServoChannel& c : config_.camera_channels) {
    if (c.output.channel >= 0 && c.output.channel < outputs_) used.push_back(c.output);
  }
  for (const ServoChannelConfig& c : used) {
    const auto i = static_cast<size_t>(c.channel);
    home_us_[i] = c.neutral_us;
    if (!sc8000) {  // the Maestro's own Min/Max settings; the SC-8000 has none
      min_us_[i] = c.min_us;
      max_us_[i] = c.max_us;
    }
  }
  HomeAll();
}

double SimServoController::output_pulse_us(int output) const {
  return output >= 0 && output < outputs_ ? output_us_[static_cast<size_t>(output)] : 0.0;
}

void SimServoController::SetOutput(int output, double pulse_us) {
  const auto i = static_cast<size_t>(output);
  output_us_[i] = std::clamp(pulse_us, min_us_[i], max_us_[i]);
  for (size_t c = 0; c < pulse_us_.size(); ++c) {
    if (config_.channels[c].channel == output) pulse_us_[c] = output_us_[i];
  }
}

void SimServoController::HomeAll() {
  output_us_ = home_us_;
  for (size_t c = 0; c < pulse_us_.size(); ++c) {
    pulse_us_[c] = output_us_[static_cast<size_t>(config_.channels[c].channel)];
  }
}

void SimServoController::Error(uint16_t bit) {
  errors_ = static_cast<uint16_t>(errors_ | bit);
  HomeAll();  // as the Maestro does on every error
}

void SimServoController::Valid(double now_s) {
  ++counters_.commands;
  last_valid_s_ = now_s;
  timed_out_ = false;
}

void SimServoController::Reply(uint16_t value) {
  const std::array<uint8_t, 2> bytes = {static_cast<uint8_t>(value & 0xFF),
                                        static_cast<uint8_t>(value >> 8)};
  counters_.reply_bytes_lost += bytes.size() - line_->Write(bytes.data(), bytes.size());
}

void SimServoController::FeedMaestro(uint8_t byte, double now_s) {
  const size_t crc = config_.crc ? 1 : 0;
  if ((byte & 0x80) != 0) {
    if (packet_need_ != 0) {  // a command interrupted by the next one
      packet_need_ = 0;
      ++counters_.frames_dropped;
      Error(maestro::kSerialProtocolError);
    }
    size_t data = 0;
    switch (byte) {
      case maestro::kSetTarget:
        data = 3;
        break;
      case maestro::kSetMultipleTargets:
        data = 2;  // then 2 per target, once the count is in
        break;
      case maestro::kGetPosition:
        data = 1;
        break;
      case maestro::kGetErrors:
      case maestro::kGoHome:
        data = 0;
        break;
      default:
        ++counters_.malformed_bytes;
        Error(maestro::kSerialProtocolError);
        return;
    }
    packet_[0] = byte;
    packet_size_ = 1;
    packet_need_ = 1 + data + crc;
  } else {
    if (packet_need_ == 0) {
      ++counters_.malformed_bytes;
      return;
    }
    packet_[packet_size_++] = byte;
    if (packet_[0] == maestro::kSetMultipleTargets && packet_size_ == 2) {
      const int count = byte;
      if (count < 1 || count > outputs_) {
        packet_need_ = 0;
        ++counters_.frames_dropped;
        Error(maestro::kSerialProtocolError);
        return;
      }
      packet_need_ = 3 + 2 * static_cast<size_t>(count) + crc;
    }
  }
  if (packet_size_ == packet_need_) ExecuteMaestro(now_s);
}

void SimServoController::ExecuteMaestro(double now_s) {
  packet_need_ = 0;
  size_t size = packet_size_;
  if (config_.crc) {
    --size;
    if (maestro::Crc7(packet_.data(), size) != packet_[size]) {
      ++counters_.crc_errors;
      ++counters_.frames_dropped;
      Error(maestro::kSerialCrcError);
      return;
    }
  }
  const auto target_at = [this](size_t at) {
    return static_cast<double>(packet_[at] | (packet_[at + 1] << 7)) / 4.0;
  };
  const auto bad = [this]() {
    ++counters_.frames_dropped;
    Error(maestro::kSerialProtocolError);
  };
  switch (packet_[0]) {
    case maestro::kSetTarget:
      if (packet_[1] >= outputs_) return bad();
      SetOutput(packet_[1], target_at(2));
      break;
    case maestro::kSetMultipleTargets: {
      const int count = packet_[1];
      const int first = packet_[2];
      if (first + count > outputs_) return bad();
      for (int k = 0; k < count; ++k)
        SetOutput(first + k, target_at(3 + 2 * static_cast<size_t>(k)));
      break;
    }
    case maestro::kGetPosition:
      if (packet_[1] >= outputs_) return bad();
      Reply(maestro::QuarterUs(output_us_[packet_[1]]));
      break;
    case maestro::kGetErrors:
      Reply(errors_);
      errors_ = 0;
      break;
    case maestro::kGoHome:
      HomeAll();
      break;
    default:
      return bad();
  }
  Valid(now_s);
}

void SimServoController::DecodeSc8000(double now_s) {
  size_t at = 0;
  while (at < pending_size_) {
    const uint8_t* p = pending_.data() + at;
    const size_t left = pending_size_ - at;
    if (p[0] != sc8000::kSync || (left >= 2 && p[1] != sc8000::kSync)) {
      ++counters_.malformed_bytes;
      ++at;
      continue;
    }
    sc8000::Decoded d;
    size_t used = 0;
    const sc8000::ParseResult r = sc8000::ParseFrame(p, left, &d, &used);
    if (r == sc8000::ParseResult::kNeedMore) break;
    if (r == sc8000::ParseResult::kInvalid) {
      ++counters_.frames_dropped;
      ++at;  // search again from the next byte: the next frame may begin inside this one
      continue;
    }
    for (int o = 0; o < sc8000::kChannels; ++o) {
      if ((d.servo_mask & (1U << o)) != 0)
        SetOutput(o, d.values_tenth_us[static_cast<size_t>(o)] / 10.0);
    }
    Valid(now_s);
    at += used;
  }
  std::memmove(pending_.data(), pending_.data() + at, pending_size_ - at);
  pending_size_ -= at;
}

void SimServoController::Update(double now_s) {
  if (!started_) {
    started_ = true;
    last_valid_s_ = now_s;
  }
  const bool sc8000 = config_.protocol == ServoProtocol::kSc8000;
  std::array<uint8_t, 256> buffer{};
  for (int reads = 0; reads < kMaxReads; ++reads) {
    if (sc8000) {
      // What is left undecoded is shorter than a frame: there is always room.
      const size_t n =
          line_->Read(pending_.data() + pending_size_, pending_.size() - pending_size_);
      if (n == 0) break;
      pending_size_ += n;
      DecodeSc8000(now_s);
    } else {
      const size_t n = line_->Read(buffer.data(), buffer.size());
      if (n == 0) break;
      for (size_t i = 0; i < n; ++i) FeedMaestro(buffer[i], now_s);
    }
  }
  if (!timed_out_ && now_s - last_valid_s_ >= config_.controller_timeout_s) {
    timed_out_ = true;
    ++counters_.timeouts;
    if (sc8000) {
      HomeAll();
    } else {
      Error(maestro::kSerialTimeout);
    }
  }
}

}  // namespace haptel::servo
