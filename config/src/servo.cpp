#include "haptel/config/servo.hpp"

#include <sstream>

#include "haptel/config/check.hpp"
#include "servo_section.hpp"

namespace haptel {

namespace check = config_check;

namespace {

constexpr std::array<const char*, kBlimpChannels> kChannelNames = {
    "elevator", "rudder", "power", "helix", "tail_rotor", "camera_pan", "camera_tilt"};

/// The rates the Maestro's UART takes that a serial port offers.
constexpr std::array<int, 8> kMaestroBauds = {1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200};
constexpr int kSc8000Baud = 9600;

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
  check::Whole("channel", channel, 0, kMaestroChannels - 1);
  check::Number("min_us", min_us, kServoMinPulse_us, kServoMaxPulse_us);
  check::Number("neutral_us", neutral_us, kServoMinPulse_us, kServoMaxPulse_us);
  check::Number("max_us", max_us, kServoMinPulse_us, kServoMaxPulse_us);
  if (!(min_us < max_us)) {
    check::Fail("min_us", "less than max_us (" + Number(max_us) + ")", {"max_us"});
  }
  if (!(neutral_us >= min_us && neutral_us <= max_us)) {
    check::Fail("neutral_us", "a number in [min_us, max_us] = " + check::Range(min_us, max_us),
                {"min_us", "max_us"});
  }
}

void ServoControllerConfig::ValidateOrThrow() const {
  for (int i = 0; i < kBlimpChannels; ++i) {
    check::Nested(std::string("channels.") + kChannelNames[static_cast<size_t>(i)],
                  channels[static_cast<size_t>(i)]);
  }
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
  check::Number("controller_timeout_s", controller_timeout_s, 0.02, 60.0);
  check::Number("error_poll_s", error_poll_s, 0.01, 60.0);
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

namespace config_detail {

ServoControllerConfig ReadServoController(YamlMap& section) {
  ServoControllerConfig c;
  const std::string protocol = section.String("protocol", ServoProtocolName(c.protocol));
  if (!ParseServoProtocol(protocol, &c.protocol))
    section.Fail("protocol", "one of: maestro, sc8000");
  c.port = section.String("port", c.port);
  c.baud = section.Integer("baud", c.protocol == ServoProtocol::kSc8000 ? kSc8000Baud : c.baud);
  c.crc = section.Bool("crc", c.crc);
  c.controller_timeout_s = section.Number("controller_timeout_s", c.controller_timeout_s);
  c.error_poll_s = section.Number("error_poll_s", c.error_poll_s);
  if (!section.IsMap("channels")) {
    section.Fail("channels",
                 "a mapping of the seven channels (elevator, rudder, power, helix, "
                 "tail_rotor, camera_pan, camera_tilt)");
  }
  YamlMap channels = section.Map("channels");
  for (int i = 0; i < kBlimpChannels; ++i) {
    const char* name = kChannelNames[static_cast<size_t>(i)];
    if (!channels.IsMap(name)) {
      channels.Fail(name,
                    std::string("the ") + name +
                        " channel (a mapping: channel, min_us, neutral_us, max_us, reversed)");
    }
    YamlMap m = channels.Map(name);
    ServoChannelConfig& ch = c.channels[static_cast<size_t>(i)];
    if (!m.Has("channel")) m.Fail("channel", "the controller's output number (a whole number)");
    ch.channel = m.Integer("channel", ch.channel);
    ch.min_us = m.Number("min_us", ch.min_us);
    ch.neutral_us = m.Number("neutral_us", ch.neutral_us);
    ch.max_us = m.Number("max_us", ch.max_us);
    ch.reversed = m.Bool("reversed", ch.reversed);
    m.Finish();
  }
  channels.Finish();
  section.Finish();
  return c;
}

}  // namespace config_detail
}  // namespace haptel
