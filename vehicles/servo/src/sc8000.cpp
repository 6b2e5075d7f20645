#include "haptel/servo/sc8000.hpp"

#include <bit>
#include <cmath>

namespace haptel::servo::sc8000 {
namespace {

constexpr char kHex[] = "0123456789ABCDEF";

/// The IO mask an ASCII hex character means; -1 for anything else.
int IoFromChar(uint8_t c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

uint16_t TenthUs(double pulse_us) {
  if (std::isnan(pulse_us)) return 15000;
  const double v = std::round(pulse_us * 10.0);
  if (v <= kMinValue) return kMinValue;
  if (v >= kMaxValue) return kMaxValue;
  return static_cast<uint16_t>(v);
}

size_t FrameBytes(uint8_t servo_mask) {
  return kHeaderBytes + 2 * static_cast<size_t>(std::popcount(servo_mask));
}

Frame MakeFrame(uint8_t servo_mask, const std::array<uint16_t, kChannels>& values_tenth_us,
                uint8_t io_mask) {
  Frame f;
  f.bytes[f.size++] = kSync;
  f.bytes[f.size++] = kSync;
  f.bytes[f.size++] = servo_mask;
  f.bytes[f.size++] = static_cast<uint8_t>(kHex[io_mask & 0x0F]);
  for (int i = 0; i < kChannels; ++i) {
    if ((servo_mask & (1U << i)) == 0) continue;
    uint16_t v = values_tenth_us[static_cast<size_t>(i)];
    v = v < kMinValue ? kMinValue : (v > kMaxValue ? kMaxValue : v);
    f.bytes[f.size++] = static_cast<uint8_t>(v >> 8);
    f.bytes[f.size++] = static_cast<uint8_t>(v & 0xFF);
  }
  return f;
}

ParseResult ParseFrame(const uint8_t* data, size_t size, Decoded* out, size_t* used) {
  if (size >= 1 && data[0] != kSync) return ParseResult::kInvalid;
  if (size >= 2 && data[1] != kSync) return ParseResult::kInvalid;
  if (size >= 4 && IoFromChar(data[3]) < 0) return ParseResult::kInvalid;
  if (size < kHeaderBytes) return ParseResult::kNeedMore;
  const uint8_t mask = data[2];
  const size_t total = FrameBytes(mask);
  // Check each value as it arrives: a truncated frame followed by the next
  // one shows as an out-of-range value (7E 7E is 32382) before the end.
  Decoded d;
  d.servo_mask = mask;
  d.io_mask = static_cast<uint8_t>(IoFromChar(data[3]));
  size_t at = kHeaderBytes;
  for (int i = 0; i < kChannels; ++i) {
    if ((mask & (1U << i)) == 0) continue;
    if (at + 2 > size) return ParseResult::kNeedMore;
    const uint16_t v = static_cast<uint16_t>((data[at] << 8) | data[at + 1]);
    if (v < kMinValue || v > kMaxValue) return ParseResult::kInvalid;
    d.values_tenth_us[static_cast<size_t>(i)] = v;
    at += 2;
  }
  *out = d;
  *used = total;
  return ParseResult::kFrame;
}

}  // namespace haptel::servo::sc8000
