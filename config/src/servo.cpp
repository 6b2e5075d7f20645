#include "haptel/config/servo.hpp"

#include <sstream>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"

namespace haptel {

namespace check = config_check;

namespace {

constexpr std::array<const char*, kBlimpChannels> kChannelNames = {
    "elevator", "rudder", "power", "helix", "tail_rotor", "camera_pan", "camera_tilt"};

/// The rates the Maestro's UART takes that a serial port offers.
constexpr std::array<int, 8> kMaestroBauds = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};

std::string Number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

std::string ChannelKey(int index, const char* field) {
  return std::string("channels.") + kChannelNames[static_cast<size_t>(index)] + "." + field;
}

}  // namespace

const char* BlimpChannelName(BlimpChannel c) {
  const int i = static_cast<int>(c);
  return i >= 0 && i < kBlimpChannels ? kChannelNames[static_cast<size_t>(i)] : "?";
}

const char* ServoProtocolName(ServoProtocol protocol) {
  switch (protocol) {
    case ServoProtocol::kMaestro:
      return "maestro";
    case ServoProtocol::kSc8000:
      return "sc8000";
  }
  return "?";
}

bool ParseServoProtocol(const std::string& name, ServoProtocol* protocol) {
  for (ServoProtocol p : {ServoProtocol::kMaestro, ServoProtocol::kSc8000}) {
    if (name == ServoProtocolName(p)) {
      *protocol = p;
      return true;
    }
  }
  return false;
}

void ServoChannelConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (!(min_us < max_us)) {
    check::Fail("min_us", "less than max_us (" + Number(max_us) + ")", {"max_us"});
  }
  if (!(neutral_us >= min_us && neutral_us <= max_us)) {
    check::Fail("neutral_us", "a number in [min_us, max_us] = " + check::Range(min_us, max_us),
                {"min_us", "max_us"});
  }
}

void ServoControllerConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  for (int i = 0; i < kBlimpChannels; ++i) {
    for (int j = 0; j < i; ++j) {
      if (channels[static_cast<size_t>(i)].channel == channels[static_cast<size_t>(j)].channel) {
        check::Fail(ChannelKey(i, "channel"),
                    std::string("an output number no other channel uses (") +
                        kChannelNames[static_cast<size_t>(j)] + " has " +
                        std::to_string(channels[static_cast<size_t>(j)].channel) + ")",
                    {ChannelKey(j, "channel")});
      }
    }
  }
  switch (protocol) {
    case ServoProtocol::kMaestro: {
      bool known = false;
      std::string rates;
      for (int rate : kMaestroBauds) {
        known = known || rate == baud;
        rates += (rates.empty() ? "" : ", ") + std::to_string(rate);
      }
      if (!known)
        check::Fail("baud", "one of " + rates + " (the Maestro's serial rates)", {"protocol"});
      break;
    }
    case ServoProtocol::kSc8000: {
      if (baud != kSc8000Baud) check::Fail("baud", "9600 (the SC-8000's only rate)", {"protocol"});
      if (crc) check::Fail("crc", "false (the SC-8000 has no CRC)", {"protocol"});
      const std::string range = check::Range(kSc8000MinPulse_us, kSc8000MaxPulse_us);
      for (int i = 0; i < kBlimpChannels; ++i) {
        const ServoChannelConfig& c = channels[static_cast<size_t>(i)];
        if (c.channel >= kSc8000Channels) {
          check::Fail(ChannelKey(i, "channel"), "a whole number in [0, 7] (the SC-8000's outputs)",
                      {"protocol"});
        }
        const std::pair<const char*, double> pulses[] = {
            {"min_us", c.min_us}, {"neutral_us", c.neutral_us}, {"max_us", c.max_us}};
        for (const auto& [field, value] : pulses) {
          if (!(value >= kSc8000MinPulse_us && value <= kSc8000MaxPulse_us)) {
            check::Fail(ChannelKey(i, field),
                        "a number in " + range + " (the SC-8000's pulse range)", {"protocol"});
          }
        }
      }
      break;
    }
  }
}

}  // namespace haptel
