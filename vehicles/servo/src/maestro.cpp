#include "haptel/servo/maestro.hpp"

#include <cmath>

namespace haptel::servo::maestro {
namespace {

void Put(Packet& p, uint8_t byte) { p.bytes[p.size++] = byte; }
void PutTarget(Packet& p, uint16_t target) {
  Put(p, static_cast<uint8_t>(target & 0x7F));
  Put(p, static_cast<uint8_t>((target >> 7) & 0x7F));
}
Packet Finish(Packet p, bool crc) {
  if (crc) Put(p, Crc7(p.data(), p.size));
  return p;
}
uint8_t ChannelByte(int channel) { return static_cast<uint8_t>(channel & 0x7F); }

}  // namespace

uint8_t Crc7(const uint8_t* data, size_t size) {
  uint8_t crc = 0;
  for (size_t i = 0; i < size; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) {
      if ((crc & 1U) != 0) crc ^= 0x91;
      crc = static_cast<uint8_t>(crc >> 1);
    }
  }
  return static_cast<uint8_t>(crc & 0x7F);
}

uint16_t QuarterUs(double pulse_us) {
  if (!(pulse_us > 0.0)) return 0;  // also NaN
  const double q = std::round(pulse_us * 4.0);
  return q >= kMaxTarget ? kMaxTarget : static_cast<uint16_t>(q);
}

Packet SetTarget(int channel, uint16_t target_quarter_us, bool crc) {
  Packet p;
  Put(p, kSetTarget);
  Put(p, ChannelByte(channel));
  PutTarget(p, target_quarter_us);
  return Finish(p, crc);
}

Packet SetMultipleTargets(int first_channel, const uint16_t* targets_quarter_us, int count,
                          bool crc) {
  if (count < 0) count = 0;
  if (count > kChannels) count = kChannels;
  Packet p;
  Put(p, kSetMultipleTargets);
  Put(p, static_cast<uint8_t>(count));
  Put(p, ChannelByte(first_channel));
  for (int i = 0; i < count; ++i) PutTarget(p, targets_quarter_us[i]);
  return Finish(p, crc);
}

Packet GetErrors(bool crc) {
  Packet p;
  Put(p, kGetErrors);
  return Finish(p, crc);
}

Packet GoHome(bool crc) {
  Packet p;
  Put(p, kGoHome);
  return Finish(p, crc);
}

Packet GetPosition(int channel, bool crc) {
  Packet p;
  Put(p, kGetPosition);
  Put(p, ChannelByte(channel));
  return Finish(p, crc);
}

}  // namespace haptel::servo::maestro
