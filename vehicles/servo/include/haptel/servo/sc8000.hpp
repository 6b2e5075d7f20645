#pragma once
/// @file Tom's RC SC-8000 serial protocol, as pure byte functions that
/// allocate nothing. Serial 9600 8N1, one way (the SC-8000 sends nothing
/// back). A frame is 7E 7E, a servo mask byte (bit i: servo i follows), the
/// digital outputs as one ASCII hex character '0'..'F' (we always send '0'),
/// then for each set bit of the mask, in increasing order, the pulse width
/// in 0.1 µs as 2 bytes, big-endian, valid 8000..22000.
#include <array>
#include <cstddef>
#include <cstdint>

namespace haptel::servo::sc8000 {

constexpr uint8_t kSync = 0x7E;
constexpr int kChannels = 8;
constexpr uint16_t kMinValue = 8000;   ///< 0.1 µs: 800 µs
constexpr uint16_t kMaxValue = 22000;  ///< 0.1 µs: 2200 µs
constexpr size_t kHeaderBytes = 4;     ///< 7E 7E, mask, IO character
constexpr size_t kMaxFrameBytes = kHeaderBytes + 2 * kChannels;

/// One frame's bytes.
struct Frame {
  std::array<uint8_t, kMaxFrameBytes> bytes{};
  size_t size = 0;
  const uint8_t* data() const { return bytes.data(); }
};

/// A pulse width in 0.1 µs, rounded, clamped to [kMinValue, kMaxValue]
/// (NaN gives 15000, 1500 µs).
uint16_t TenthUs(double pulse_us);

/// The size of a frame for `servo_mask`: 4 + 2 per set bit.
size_t FrameBytes(uint8_t servo_mask);

/// A frame setting the servos of `servo_mask` to `values_tenth_us[i]` (by
/// servo number; entries of clear bits are ignored; values are clamped to
/// the valid range). `io_mask` (0..15) sets the digital outputs.
Frame MakeFrame(uint8_t servo_mask, const std::array<uint16_t, kChannels>& values_tenth_us,
                uint8_t io_mask = 0);

/// A frame as decoded: which servos it sets, to what, and the IO mask.
struct Decoded {
  uint8_t servo_mask = 0;
  uint8_t io_mask = 0;
  std::array<uint16_t, kChannels> values_tenth_us{};  ///< set for the mask's bits
};

enum class ParseResult {
  kFrame,     ///< a valid frame of `*used` bytes
  kNeedMore,  ///< a frame's beginning: wait for more bytes
  kInvalid,   ///< not a valid frame here (no 7E 7E, a bad IO character, a value out of range)
};

/// Parses a frame at the start of `data`. kFrame fills `out` and `used`;
/// the others leave them.
ParseResult ParseFrame(const uint8_t* data, size_t size, Decoded* out, size_t* used);

}  // namespace haptel::servo::sc8000
