// The blimp's servo controller: the Maestro and SC-8000 bytes against the
// documentation and hand-computed frames, the channel calibration and its
// config, the adapter's output against the simulated controller through a
// real pseudo-terminal (pulses, the error register, the controller's own
// timeout), resynchronisation after garbage, a fuzz run of both decoders,
// and a port that vanishes. Time is the `now_s` argument (a fake clock);
// waits for bytes to cross the pty poll with deadlines.
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <deque>
#include <random>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/servo.hpp"
#include "haptel/servo/calibration.hpp"
#include "haptel/servo/maestro.hpp"
#include "haptel/servo/sc8000.hpp"
#include "haptel/servo/serial_port.hpp"
#include "haptel/servo/servo_output.hpp"
#include "haptel/servo/sim_servo_controller.hpp"
#include "servo_section.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::servo;
using Bytes = std::vector<uint8_t>;

namespace {

constexpr double kWait_s = 30.0;  // bounds a wait for bytes to cross the pty; asserts no timing

Bytes Of(const maestro::Packet& p) {
  return {p.bytes.begin(), p.bytes.begin() + static_cast<long>(p.size)};
}
Bytes Of(const sc8000::Frame& f) {
  return {f.bytes.begin(), f.bytes.begin() + static_cast<long>(f.size)};
}

/// Seven channels with different calibrations; the Maestro's outputs are
/// scattered (and out of order) to check the mapping, the SC-8000's are a
/// permutation of 0..6.
ServoControllerConfig Configured(ServoProtocol protocol, bool crc = false) {
  ServoControllerConfig c;
  c.protocol = protocol;
  c.crc = crc;
  c.baud = protocol == ServoProtocol::kSc8000 ? 9600 : 115200;
  const bool sc = protocol == ServoProtocol::kSc8000;
  c.channels[0] = {sc ? 6 : 12, 1100, 1500, 1900, false};  // elevator
  c.channels[1] = {sc ? 1 : 1, 1000, 1500, 2000, true};    // rudder
  c.channels[2] = {sc ? 2 : 23, 1000, 1000, 2000, false};  // power
  c.channels[3] = {sc ? 3 : 3, 1200, 1500, 1800, false};   // helix
  c.channels[4] = {sc ? 4 : 0, 1000, 1500, 2000, false};   // tail rotor
  c.channels[5] = {sc ? 5 : 7, 900, 1500, 2100, false};    // camera pan
  c.channels[6] = {sc ? 0 : 6, 1100, 1400, 1700, true};    // camera tilt
  return c;
}

/// Pulses within every channel of Configured() (on the quarter-µs grid
/// and the 0.1 µs one, so both protocols carry them exactly).
std::array<double, kBlimpChannels> SomePulses(double shift = 0.0) {
  return {1250.5 + shift, 1900.0 - shift, 1000.0 + shift, 1799.0 - shift,
          1500.5 + shift, 925.5 + shift,  1699.5 - shift};
}

/// A stream in memory: the test puts bytes in, and reads what was written.
/// `accept` limits how many bytes one Write takes (a full port).
class MemoryStream final : public ByteStream {
 public:
  std::deque<uint8_t> in;
  Bytes out;
  size_t accept = SIZE_MAX;
  size_t Write(const uint8_t* data, size_t size) override {
    const size_t n = std::min(size, accept);
    out.insert(out.end(), data, data + n);
    return n;
  }
  size_t Read(uint8_t* data, size_t size) override {
    size_t n = 0;
    while (n < size && !in.empty()) {
      data[n++] = in.front();
      in.pop_front();
    }
    return n;
  }
  std::string name() const override { return "memory"; }
  void Put(const Bytes& bytes) { in.insert(in.end(), bytes.begin(), bytes.end()); }
};

/// A simulated controller fed from memory.
struct MemorySim {
  MemoryStream* line;
  std::unique_ptr<SimServoController> sim;
  explicit MemorySim(const ServoControllerConfig& config) {
    auto stream = std::make_unique<MemoryStream>();
    line = stream.get();
    sim = std::make_unique<SimServoController>(config, std::move(stream));
  }
  void Feed(const Bytes& bytes, double now_s = 0.0) {
    line->Put(bytes);
    sim->Update(now_s);
  }
};

/// The adapter's output on a SerialPort opened on a pty's slave path, and
/// the simulated controller on its master end.
struct PtyBench {
  PtyPair pty;
  std::unique_ptr<ServoOutput> output;
  std::unique_ptr<SimServoController> sim;
  explicit PtyBench(const ServoControllerConfig& config) {
    output = std::make_unique<ServoOutput>(
        config, std::make_unique<SerialPort>(pty.slave_path(), config.baud));
    sim = std::make_unique<SimServoController>(config, pty.TakeMaster());
  }
  /// Updates the controller (and the output when `output_too`) at `now_s`
  /// until `done` holds; false if it never does within kWait_s.
  template <typename Done>
  bool Pump(double now_s, Done done, bool output_too = false) {
    const test::Deadline deadline(kWait_s);
    for (;;) {
      sim->Update(now_s);
      if (output_too) output->Update(now_s);
      if (done()) return true;
      if (deadline.passed()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  bool CommandsReach(double now_s, uint64_t n, bool output_too = false) {
    return Pump(
        now_s, [&] { return sim->counters().commands >= n; }, output_too);
  }
};

}  // namespace

// --- the protocols' bytes ---------------------------------------------------

TEST_CASE("Maestro commands are the bytes the Pololu documentation gives") {
  CHECK(maestro::QuarterUs(1500.0) == 6000);
  CHECK(Of(maestro::SetTarget(2, 6000, false)) == Bytes{0x84, 0x02, 0x70, 0x2E});
  const uint8_t crc_example[] = {0x83, 0x01};
  CHECK(maestro::Crc7(crc_example, 2) == 0x17);
  CHECK(Of(maestro::GoHome(false)) == Bytes{0xA2});
  CHECK(Of(maestro::GetErrors(false)) == Bytes{0xA1});
  CHECK(Of(maestro::GetPosition(5, false)) == Bytes{0x90, 0x05});
  // With CRC each command carries its CRC-7 byte.
  const Bytes with_crc = Of(maestro::SetTarget(2, 6000, true));
  REQUIRE(with_crc.size() == 5);
  CHECK(Bytes(with_crc.begin(), with_crc.begin() + 4) == Bytes{0x84, 0x02, 0x70, 0x2E});
  CHECK(with_crc[4] == maestro::Crc7(with_crc.data(), 4));
  CHECK(with_crc[4] < 0x80);
  CHECK(Of(maestro::GoHome(true)) == Bytes{0xA2, maestro::Crc7(Bytes{0xA2}.data(), 1)});
  // Set Multiple Targets: count, first channel, then low/high per target.
  const uint16_t targets[] = {6000, 4000};
  CHECK(Of(maestro::SetMultipleTargets(3, targets, 2, false)) ==
        Bytes{0x9F, 0x02, 0x03, 0x70, 0x2E, 0x20, 0x1F});
  // Quarter-µs rounding and the 14-bit limit.
  CHECK(maestro::QuarterUs(1500.1) == 6000);
  CHECK(maestro::QuarterUs(1500.2) == 6001);
  CHECK(maestro::QuarterUs(1e9) == maestro::kMaxTarget);
  CHECK(maestro::QuarterUs(std::nan("")) == 0);
}

TEST_CASE("Maestro replies and error bits read as documented") {
  CHECK(maestro::ReplyValue(0x20, 0x00) == maestro::kSerialTimeout);
  CHECK(maestro::ReplyValue(0x08, 0x01) ==
        (maestro::kSerialCrcError | maestro::kScriptProgramCounterError));
  CHECK(maestro::ReplyValue(0x70, 0x17) == 0x1770);  // a position: 6000 quarter-µs
  CHECK(maestro::ErrorNames(0) == "none");
  CHECK(maestro::ErrorNames(maestro::kSerialTimeout | maestro::kSerialCrcError) ==
        "serial timeout, CRC error");
  CHECK(maestro::ErrorNames(maestro::kSerialProtocolError) == "protocol error");
  CHECK(maestro::ErrorNames(1U << 8) == "script program counter error");
  CHECK(maestro::ErrorNames(1U << 0 | 1U << 1 | 1U << 2) ==
        "serial RX buffer full, serial overrun, serial signal error");
  CHECK(maestro::ErrorNames(1U << 12) == "bit 12");
}

TEST_CASE("SC-8000 frames match hand-computed bytes") {
  std::array<uint16_t, sc8000::kChannels> values{};
  values[0] = 15000;  // 0x3A98: 1500 µs
  values[2] = 8000;   // 0x1F40
  values[1] = 12345;  // not in the mask: not sent
  CHECK(Of(sc8000::MakeFrame(0x05, values)) ==
        Bytes{0x7E, 0x7E, 0x05, '0', 0x3A, 0x98, 0x1F, 0x40});
  values[7] = 22000;  // 0x55F0
  CHECK(Of(sc8000::MakeFrame(0x84, values, 0x0B)) ==
        Bytes{0x7E, 0x7E, 0x84, 'B', 0x1F, 0x40, 0x55, 0xF0});
  CHECK(Of(sc8000::MakeFrame(0x00, values)) == Bytes{0x7E, 0x7E, 0x00, '0'});
  CHECK(sc8000::FrameBytes(0x7F) == 18);
  CHECK(sc8000::TenthUs(1500.0) == 15000);
  CHECK(sc8000::TenthUs(1234.56) == 12346);
  CHECK(sc8000::TenthUs(500.0) == sc8000::kMinValue);
  CHECK(sc8000::TenthUs(3000.0) == sc8000::kMaxValue);
  CHECK(sc8000::TenthUs(std::nan("")) == 15000);

  const Bytes frame = Of(sc8000::MakeFrame(0x05, values));
  sc8000::Decoded d;
  size_t used = 0;
  REQUIRE(sc8000::ParseFrame(frame.data(), frame.size(), &d, &used) == sc8000::ParseResult::kFrame);
  CHECK(used == frame.size());
  CHECK(d.servo_mask == 0x05);
  CHECK(d.values_tenth_us[0] == 15000);
  CHECK(d.values_tenth_us[2] == 8000);
  CHECK(sc8000::ParseFrame(frame.data(), frame.size() - 1, &d, &used) ==
        sc8000::ParseResult::kNeedMore);
  Bytes bad_io = frame;
  bad_io[3] = 'g';
  CHECK(sc8000::ParseFrame(bad_io.data(), bad_io.size(), &d, &used) ==
        sc8000::ParseResult::kInvalid);
  Bytes out_of_range = frame;
  out_of_range[4] = 0x7E;  // 0x7E98 > 22000
  CHECK(sc8000::ParseFrame(out_of_range.data(), out_of_range.size(), &d, &used) ==
        sc8000::ParseResult::kInvalid);
}

// --- calibration and config -------------------------------------------------

TEST_CASE("Channel calibration maps commands to pulses and back") {
  const ServoChannelConfig elevator{0, 1100, 1500, 1900, false};
  CHECK(PulseFromCommand(elevator, 0.0) == 1500.0);
  CHECK(PulseFromCommand(elevator, 1.0) == 1900.0);
  CHECK(PulseFromCommand(elevator, -1.0) == 1100.0);
  CHECK(PulseFromCommand(elevator, 0.5) == 1700.0);
  CHECK(PulseFromCommand(elevator, 7.0) == 1900.0);  // clamped
  CHECK(PulseFromCommand(elevator, -7.0) == 1100.0);
  CHECK(PulseFromCommand(elevator, std::nan("")) == 1500.0);
  CHECK(PulseFromCommand(elevator, INFINITY) == 1900.0);

  const ServoChannelConfig trimmed{0, 1000, 1600, 1800, false};  // sides of different spans
  CHECK(PulseFromCommand(trimmed, 0.5) == 1700.0);
  CHECK(PulseFromCommand(trimmed, -0.5) == 1300.0);

  const ServoChannelConfig reversed{0, 1100, 1500, 1900, true};
  CHECK(PulseFromCommand(reversed, 1.0) == 1100.0);
  CHECK(PulseFromCommand(reversed, -0.25) == 1600.0);
  CHECK(PulseFromCommand(reversed, 0.0) == 1500.0);

  const ServoChannelConfig power{2, 1000, 1000, 2000, false};
  CHECK(PulseFromCommand(power, 0.0) == 1000.0);
  CHECK(PulseFromCommand(power, 0.3) == Approx(1300.0));
  CHECK(PulseFromCommand(power, -1.0) == 1000.0);  // no travel below neutral
  CHECK(CommandFromPulse(power, 900.0) == 0.0);

  for (const ServoChannelConfig& c : {elevator, trimmed, reversed, power}) {
    const double lo = c.neutral_us == c.min_us ? (c.reversed ? -1.0 : 0.0) : -1.0;
    const double hi = c.neutral_us == c.min_us ? (c.reversed ? 0.0 : 1.0) : 1.0;
    for (int k = 0; k <= 40; ++k) {
      const double v = lo + (hi - lo) * k / 40.0;
      CHECK(CommandFromPulse(c, PulseFromCommand(c, v)) == Approx(v).margin(1e-12));
    }
  }
  CHECK(CommandFromPulse(elevator, 5000.0) == 1.0);  // clamped
  CHECK(CommandFromPulse(elevator, 0.0) == -1.0);
  CHECK(CommandFromPulse(reversed, 1900.0) == -1.0);
  CHECK(CommandFromPulse(elevator, std::nan("")) == 0.0);

  const ServoControllerConfig config = Configured(ServoProtocol::kMaestro);
  const auto neutral = NeutralPulses(config);
  CHECK(PulsesFromCommands(config, {0, 0, 0, 0, 0, 0, 0}) == neutral);
  CHECK(PulsesFromCommands(config, {1, 1, 1, 1, 1, 1, 1})[1] == 1000.0);  // rudder reversed
}

TEST_CASE("A channel's calibration errors name the channel") {
  ServoControllerConfig c = Configured(ServoProtocol::kMaestro);
  REQUIRE_NOTHROW(c.ValidateOrThrow());
  const auto key_of = [](const ServoControllerConfig& config) {
    try {
      config.ValidateOrThrow();
    } catch (const ConfigFieldError& e) {
      return e.key;
    }
    return std::string("(no error)");
  };
  SECTION("min_us >= max_us") {
    c.channels[static_cast<int>(BlimpChannel::kRudder)].min_us = 2000;
    CHECK(key_of(c) == "channels.rudder.min_us");
    CHECK_THROWS_WITH(c.ValidateOrThrow(),
                      Catch::Contains("channels.rudder.min_us: expected less than max_us"));
  }
  SECTION("neutral outside [min, max]") {
    c.channels[static_cast<int>(BlimpChannel::kHelix)].neutral_us = 1900;
    CHECK(key_of(c) == "channels.helix.neutral_us");
    CHECK_THROWS_WITH(c.ValidateOrThrow(), Catch::Contains("[1200, 1800]"));
  }
  SECTION("a pulse no servo takes") {
    c.channels[static_cast<int>(BlimpChannel::kCameraTilt)].max_us = 3000;
    CHECK(key_of(c) == "channels.camera_tilt.max_us");
  }
  SECTION("two channels on one output") {
    c.channels[static_cast<int>(BlimpChannel::kTailRotor)].channel = 12;  // the elevator's
    CHECK(key_of(c) == "channels.tail_rotor.channel");
    CHECK_THROWS_WITH(c.ValidateOrThrow(), Catch::Contains("elevator has 12"));
  }
  SECTION("Maestro outputs end at 23") {
    c.channels[0].channel = 24;
    CHECK(key_of(c) == "channels.elevator.channel");
  }
  SECTION("Maestro baud rates") {
    c.baud = 12345;
    CHECK(key_of(c) == "baud");
  }
  SECTION("timeouts") {
    c.controller_timeout_s = 0.0;
    CHECK(key_of(c) == "controller_timeout_s");
  }
  SECTION("the SC-8000's narrower limits") {
    ServoControllerConfig s = Configured(ServoProtocol::kSc8000);
    REQUIRE_NOTHROW(s.ValidateOrThrow());
    s.channels[static_cast<int>(BlimpChannel::kPower)].channel = 9;
    CHECK(key_of(s) == "channels.power.channel");
    s = Configured(ServoProtocol::kSc8000);
    s.channels[static_cast<int>(BlimpChannel::kCameraPan)].min_us = 700;  // fine for a Maestro
    CHECK(key_of(s) == "channels.camera_pan.min_us");
    CHECK_THROWS_WITH(s.ValidateOrThrow(), Catch::Contains("SC-8000"));
    s = Configured(ServoProtocol::kSc8000);
    s.baud = 115200;
    CHECK(key_of(s) == "baud");
    s = Configured(ServoProtocol::kSc8000);
    s.crc = true;
    CHECK(key_of(s) == "crc");
  }
  CHECK(std::string(BlimpChannelName(BlimpChannel::kTailRotor)) == "tail_rotor");
  CHECK(std::string(BlimpChannelName(BlimpChannel::kCameraTilt)) == "camera_tilt");
}

namespace {

const char* kServoYaml = R"(servo:
  protocol: maestro
  port: /dev/ttyACM0
  baud: 57600
  crc: true
  controller_timeout_s: 0.25
  error_poll_s: 0.2
  channels:
    elevator:    {channel: 0, min_us: 1100, neutral_us: 1500, max_us: 1900, reversed: false}
    rudder:      {channel: 1, min_us: %RUDDER_MIN%, neutral_us: 1500, max_us: 1900, reversed: true}
    power:       {channel: 2, min_us: 1000, neutral_us: 1000, max_us: 2000}
    helix:       {channel: 3}
    tail_rotor:  {channel: 4}
    camera_pan:  {channel: 5, min_us: 800, max_us: 2200}
    camera_tilt: {channel: 6}%EXTRA%
)";

/// The servo section of a file written from kServoYaml, read and validated.
ServoControllerConfig ReadFile(const std::string& rudder_min, const std::string& extra = "") {
  std::string text = kServoYaml;
  text.replace(text.find("%RUDDER_MIN%"), 12, rudder_min);
  text.replace(text.find("%EXTRA%"), 7, extra);
  static int n = 0;
  const auto file = test::WriteFile(
      test::ScratchDir("servo-config") / ("servo" + std::to_string(++n) + ".yaml"), text);
  config_detail::YamlMap root = config_detail::YamlMap::Load(file);
  config_detail::YamlMap section = root.Map("servo");
  const ServoControllerConfig c = config_detail::ReadServoController(section);
  config_detail::ValidateIn(section, c);
  return c;
}

}  // namespace

TEST_CASE("The servo section reads strictly from a file, errors at the channel's key") {
  const ServoControllerConfig c = ReadFile("1100");
  CHECK(c.protocol == ServoProtocol::kMaestro);
  CHECK(c.port == "/dev/ttyACM0");
  CHECK(c.baud == 57600);
  CHECK(c.crc);
  CHECK(c.controller_timeout_s == 0.25);
  CHECK(c.error_poll_s == 0.2);
  CHECK(c.channels[1].reversed);
  CHECK(c.channels[1].min_us == 1100);
  CHECK(c.channels[2].neutral_us == 1000);
  CHECK(c.channels[5].min_us == 800);
  CHECK(c.channels[6].channel == 6);
  CHECK(c.channels[6].neutral_us == 1500);  // default

  const std::string bad = test::WhatOf<ConfigError>([] { ReadFile("1950"); });
  CHECK_THAT(bad, Catch::Contains("key 'servo.channels.rudder.min_us'") &&
                      Catch::Contains("less than max_us") && Catch::Contains(".yaml:10:"));
  CHECK_THAT(test::WhatOf<ConfigError>([] { ReadFile("1100", "\n    winch: {channel: 7}"); }),
             Catch::Contains("servo.channels.winch") && Catch::Contains("unknown key"));
  CHECK_THAT(test::WhatOf<ConfigError>([] { ReadFile("1100", "\n  speed: 3"); }),
             Catch::Contains("servo.speed") && Catch::Contains("unknown key"));
  CHECK_THAT(test::WhatOf<ConfigError>([] { ReadFile("1100, mid_us: 3"); }),
             Catch::Contains("servo.channels.rudder.mid_us"));
}

TEST_CASE("The servo section needs all seven channels and a known protocol") {
  const auto dir = test::ScratchDir("servo-config-missing");
  const auto read = [&](const std::string& text) {
    const auto file = test::WriteFile(dir / "servo.yaml", text);
    config_detail::YamlMap root = config_detail::YamlMap::Load(file);
    config_detail::YamlMap section = root.Map("servo");
    return config_detail::ReadServoController(section);
  };
  CHECK_THAT(test::WhatOf<ConfigError>([&] { read("servo:\n  protocol: pwm\n"); }),
             Catch::Contains("servo.protocol") && Catch::Contains("maestro, sc8000"));
  CHECK_THAT(test::WhatOf<ConfigError>([&] { read("servo:\n  protocol: maestro\n"); }),
             Catch::Contains("servo.channels") && Catch::Contains("seven channels"));
  CHECK_THAT(
      test::WhatOf<ConfigError>([&] { read("servo:\n  channels:\n    elevator: {channel: 0}\n"); }),
      Catch::Contains("servo.channels.rudder"));
  CHECK_THAT(test::WhatOf<ConfigError>(
                 [&] { read("servo:\n  channels:\n    elevator: {min_us: 1000}\n"); }),
             Catch::Contains("servo.channels.elevator.channel"));
  // The SC-8000's baud defaults to its only rate.
  const ServoControllerConfig s = read(
      "servo:\n  protocol: sc8000\n  channels:\n    elevator: {channel: 0}\n    rudder: {channel: "
      "1}\n"
      "    power: {channel: 2}\n    helix: {channel: 3}\n    tail_rotor: {channel: 4}\n"
      "    camera_pan: {channel: 5}\n    camera_tilt: {channel: 7}\n");
  CHECK(s.protocol == ServoProtocol::kSc8000);
  CHECK(s.baud == 9600);
  CHECK(s.port.empty());
  CHECK_NOTHROW(s.ValidateOrThrow());
}

// --- end to end through a real pty ------------------------------------------

TEST_CASE("Pulses cross a real pty to the simulated controller exactly") {
  ServoProtocol protocol = ServoProtocol::kMaestro;
  bool crc = false;
  const int kind = GENERATE(0, 1, 2);  // Maestro, Maestro with CRC, SC-8000
  if (kind == 1) crc = true;
  if (kind == 2) protocol = ServoProtocol::kSc8000;
  const ServoControllerConfig config = Configured(protocol, crc);
  PtyBench bench(config);
  // Starts at home.
  bench.sim->Update(0.0);
  CHECK(bench.sim->pulse_us() == NeutralPulses(config));

  const uint64_t per_send = protocol == ServoProtocol::kMaestro ? kBlimpChannels : 1;
  uint64_t expected = 0;
  for (int round = 0; round < 20; ++round) {
    const auto pulses = SomePulses(round * 2.5);
    bench.output->Send(pulses);
    expected += per_send;
    REQUIRE(bench.CommandsReach(0.01 * round, expected));
    CHECK(bench.sim->pulse_us() == pulses);
  }
  CHECK(bench.output->counters().frames_sent == 20);
  CHECK(bench.output->counters().write_short == 0);
  CHECK(bench.sim->counters().malformed_bytes == 0);
  CHECK(bench.sim->counters().frames_dropped == 0);
  CHECK(bench.sim->errors() == 0);
  // The controller's outputs: elevator on 12 (Maestro) / 6 (SC-8000).
  CHECK(bench.sim->output_pulse_us(config.channels[0].channel) == bench.sim->pulse_us()[0]);

  SECTION("out-of-range and NaN pulses are clamped to the channel before the wire") {
    std::array<double, kBlimpChannels> wild = SomePulses();
    wild[0] = 5000.0;
    wild[3] = std::nan("");
    wild[5] = -3.0;
    bench.output->Send(wild);
    REQUIRE(bench.CommandsReach(0.2, expected + per_send));
    CHECK(bench.sim->pulse_us()[0] == 1900.0);
    CHECK(bench.sim->pulse_us()[3] == 1500.0);
    CHECK(bench.sim->pulse_us()[5] == 900.0);
  }
  SECTION("Go Home sends every channel to neutral") {
    bench.output->GoHome();
    REQUIRE(bench.CommandsReach(0.2, expected + 1));
    CHECK(bench.sim->pulse_us() == NeutralPulses(config));
  }
}

TEST_CASE("The Maestro's error register round-trips through Get Errors") {
  ServoControllerConfig config = Configured(ServoProtocol::kMaestro, true);
  config.controller_timeout_s = 5.0;  // no timeout while the fake clock jumps between polls
  PtyBench bench(config);
  ServoOutput& out = *bench.output;
  // The first Update asks at once: no errors yet.
  REQUIRE(bench.Pump(
      0.0, [&] { return out.counters().error_replies == 1; }, true));
  CHECK(out.last_errors() == 0);
  // Not again before error_poll_s.
  out.Update(0.1);
  CHECK(out.counters().frames_sent == 1);

  // A Set Target with a wrong CRC, written on the line (our own slave
  // descriptor): dropped, the CRC error bit set, every output home.
  bench.output->Send(SomePulses());
  REQUIRE(bench.CommandsReach(0.1, 1 + kBlimpChannels));
  maestro::Packet corrupt = maestro::SetTarget(12, 7000, true);
  corrupt.bytes[4] ^= 0x01;
  REQUIRE(::write(bench.pty.slave_fd(), corrupt.data(), corrupt.size) ==
          static_cast<ssize_t>(corrupt.size));
  REQUIRE(bench.Pump(0.1, [&] { return bench.sim->counters().crc_errors == 1; }));
  CHECK(bench.sim->errors() == maestro::kSerialCrcError);
  CHECK(bench.sim->pulse_us() == NeutralPulses(config));

  out.Update(0.5);  // the next poll
  REQUIRE(bench.Pump(
      0.5, [&] { return out.counters().error_replies == 2; }, true));
  CHECK(out.last_errors() == maestro::kSerialCrcError);
  CHECK(maestro::ErrorNames(out.last_errors()) == "CRC error");
  CHECK(bench.sim->errors() == 0);  // cleared by reading it

  // A protocol error (an unknown command byte) the same way; the reply
  // after it is clean again.
  const uint8_t unknown = 0xAB;
  REQUIRE(::write(bench.pty.slave_fd(), &unknown, 1) == 1);
  REQUIRE(bench.Pump(0.5, [&] { return bench.sim->errors() != 0; }));
  REQUIRE(bench.Pump(
      1.0, [&] { return out.counters().error_replies == 3; }, true));
  CHECK(out.last_errors() == maestro::kSerialProtocolError);
  REQUIRE(bench.Pump(
      1.5, [&] { return out.counters().error_replies == 4; }, true));
  CHECK(out.last_errors() == 0);
  CHECK(out.errors_seen() == (maestro::kSerialCrcError | maestro::kSerialProtocolError));
  CHECK(out.counters().unexpected_bytes == 0);
  CHECK(out.counters().replies_missing == 0);
}

TEST_CASE("The controller's own failsafe: silence sends every channel home") {
  const bool maestro_protocol = GENERATE(true, false);
  const ServoControllerConfig config = Configured(
      maestro_protocol ? ServoProtocol::kMaestro : ServoProtocol::kSc8000, maestro_protocol);
  PtyBench bench(config);
  const uint64_t per_send = maestro_protocol ? kBlimpChannels : 1;
  uint64_t expected = 0;
  double t = 0.0;
  for (; t < 1.0; t += 0.02) {  // a 50 Hz vehicle loop on the fake clock
    bench.output->Send(SomePulses());
    expected += per_send;
    REQUIRE(bench.CommandsReach(t, expected));
    REQUIRE_FALSE(bench.sim->timed_out());
  }
  CHECK(bench.sim->pulse_us() == SomePulses());
  // The output stops; the controller holds until its timeout (0.5 s).
  const double last = t - 0.02;
  bench.sim->Update(last + 0.3);
  CHECK_FALSE(bench.sim->timed_out());
  CHECK(bench.sim->pulse_us() == SomePulses());
  bench.sim->Update(last + 0.51);
  CHECK(bench.sim->timed_out());
  CHECK(bench.sim->pulse_us() == NeutralPulses(config));
  CHECK(bench.sim->counters().timeouts == 1);
  bench.sim->Update(last + 5.0);
  CHECK(bench.sim->counters().timeouts == 1);  // once per silence
  if (maestro_protocol) {
    CHECK(bench.sim->errors() == maestro::kSerialTimeout);
    // The adapter reads the timeout bit with its next poll.
    REQUIRE(bench.Pump(
        last + 5.0, [&] { return bench.output->counters().error_replies == 1; }, true));
    CHECK(bench.output->last_errors() == maestro::kSerialTimeout);
    expected += 1;
  } else {
    CHECK(bench.sim->errors() == 0);  // the SC-8000 has no error register
  }
  // Sending again resumes.
  bench.output->Send(SomePulses(5.0));
  expected += per_send;
  REQUIRE(bench.CommandsReach(last + 5.1, expected));
  CHECK_FALSE(bench.sim->timed_out());
  CHECK(bench.sim->pulse_us() == SomePulses(5.0));
}

// --- resynchronisation and fuzzing ------------------------------------------

TEST_CASE("The simulated Maestro resynchronises after garbage") {
  const bool crc = GENERATE(false, true);
  const ServoControllerConfig config = Configured(ServoProtocol::kMaestro, crc);
  MemorySim m(config);
  const Bytes valid = Of(maestro::SetTarget(12, 7000, crc));  // elevator: 1750 µs
  const auto elevator = [&] { return m.sim->pulse_us()[0]; };

  SECTION("data bytes outside any command") {
    m.Feed({0x01, 0x7F, 0x00, 0x55});
    CHECK(m.sim->counters().malformed_bytes == 4);
    CHECK(m.sim->errors() == 0);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("a truncated command interrupted by the next") {
    m.Feed({0x84, 0x0C, 0x10});
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
    CHECK(m.sim->errors() == maestro::kSerialProtocolError);
    CHECK(m.sim->counters().frames_dropped == 1);
    CHECK(m.sim->counters().commands == 1);
  }
  SECTION("a byte with bit 7 set in a data position") {
    m.Feed({0x84, 0x0C, 0xFF, 0x2E});
    CHECK(m.sim->errors() == maestro::kSerialProtocolError);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("an unknown command byte") {
    m.Feed({0x80});
    CHECK(m.sim->errors() == maestro::kSerialProtocolError);
    CHECK(m.sim->counters().malformed_bytes == 1);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("an output that does not exist") {
    m.Feed(Of(maestro::SetTarget(30, 6000, crc)));
    CHECK(m.sim->errors() == maestro::kSerialProtocolError);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("random garbage between valid commands") {
    std::mt19937 rng(7);
    for (int k = 0; k < 200; ++k) {
      Bytes junk(rng() % 12);
      for (uint8_t& b : junk) b = static_cast<uint8_t>(rng());
      m.Feed(junk);
      const uint16_t target = static_cast<uint16_t>(4400 + rng() % 3200);  // 1100..1900 µs
      m.Feed(Of(maestro::SetTarget(12, target, crc)));
      REQUIRE(elevator() == target / 4.0);
    }
    CHECK(m.sim->counters().commands >= 200);
  }
  // Every error sent the outputs home; what was set since stands.
  CHECK(m.sim->pulse_us()[1] == 1500.0);
}

TEST_CASE("The simulated SC-8000 resynchronises after garbage") {
  const ServoControllerConfig config = Configured(ServoProtocol::kSc8000);
  MemorySim m(config);
  std::array<uint16_t, sc8000::kChannels> values{};
  values.fill(15000);
  values[6] = 17500;  // elevator: 1750 µs
  const Bytes valid = Of(sc8000::MakeFrame(0x7F, values));
  const auto elevator = [&] { return m.sim->pulse_us()[0]; };

  SECTION("bytes outside frames") {
    m.Feed({0x01, 0x7E, 0x30, 0x55});
    CHECK(m.sim->counters().malformed_bytes == 4);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
    CHECK(m.sim->counters().commands == 1);
  }
  SECTION("a truncated frame followed by a whole one") {
    m.Feed(Bytes(valid.begin(), valid.begin() + 9));
    CHECK(m.sim->counters().commands == 0);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
    CHECK(m.sim->counters().frames_dropped >= 1);
    CHECK(m.sim->counters().commands == 1);
  }
  SECTION("a value out of range drops the frame") {
    std::array<uint16_t, sc8000::kChannels> wild = values;
    Bytes frame = Of(sc8000::MakeFrame(0x7F, wild));
    frame[4] = 0x60;  // 0x60xx > 22000
    m.Feed(frame);
    CHECK(m.sim->counters().commands == 0);
    CHECK(m.sim->counters().frames_dropped >= 1);
    CHECK(elevator() == 1500.0);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("a bad IO character") {
    Bytes frame = valid;
    frame[3] = 'x';
    m.Feed(frame);
    CHECK(m.sim->counters().commands == 0);
    m.Feed(valid);
    CHECK(elevator() == 1750.0);
  }
  SECTION("a frame split across reads") {
    m.Feed(Bytes(valid.begin(), valid.begin() + 5));
    m.Feed(Bytes(valid.begin() + 5, valid.end()));
    CHECK(elevator() == 1750.0);
    CHECK(m.sim->counters().frames_dropped == 0);
  }
}

TEST_CASE("A fuzz of 10^5 random byte strings never crashes the decoders") {
  const int kind = GENERATE(0, 1, 2);  // Maestro, Maestro with CRC, SC-8000
  const ServoControllerConfig config =
      Configured(kind == 2 ? ServoProtocol::kSc8000 : ServoProtocol::kMaestro, kind == 1);
  MemorySim m(config);
  std::mt19937 rng(1234U + static_cast<unsigned>(kind));
  // Bytes the decoders care about, often; anything, otherwise.
  const uint8_t special[] = {0x84, 0x9F, 0x90, 0xA1, 0xA2, 0x7E, 0x7E,
                             0x30, 0x00, 0x7F, 0x17, 0x3A, 0x55};
  const double lo = kind == 2 ? kSc8000MinPulse_us : kServoMinPulse_us;
  const double hi = kind == 2 ? kSc8000MaxPulse_us : kServoMaxPulse_us;
  uint64_t in_range = 0;
  Bytes junk;
  for (int k = 0; k < 100000; ++k) {
    junk.resize(rng() % 40);
    for (uint8_t& b : junk)
      b = rng() % 3 == 0 ? special[rng() % sizeof special] : static_cast<uint8_t>(rng());
    m.Feed(junk, k * 1e-3);
    bool ok = true;
    for (double p : m.sim->pulse_us()) ok = ok && p >= lo && p <= hi;
    in_range += ok ? 1 : 0;
    if (k % 97 == 0) {
      // A valid command after the garbage is obeyed (the SC-8000: the second
      // of two frames, since a garbage frame may swallow the first's first byte).
      if (kind == 2) {
        std::array<uint16_t, sc8000::kChannels> values{};
        values.fill(static_cast<uint16_t>(12000 + k % 5000));
        const Bytes frame = Of(sc8000::MakeFrame(0x7F, values));
        m.Feed(frame, k * 1e-3);
        m.Feed(frame, k * 1e-3);
        REQUIRE(m.sim->pulse_us()[3] == values[3] / 10.0);
      } else {
        const uint16_t target =
            static_cast<uint16_t>(4800 + k % 2400);  // within the helix's 1200..1800
        m.Feed(Of(maestro::SetTarget(3, target, kind == 1)), k * 1e-3);
        REQUIRE(m.sim->pulse_us()[3] == target / 4.0);
      }
    }
  }
  CHECK(in_range == 100000);
  const SimServoCounters& c = m.sim->counters();
  INFO("commands " << c.commands << ", malformed " << c.malformed_bytes << ", dropped "
                   << c.frames_dropped << ", crc " << c.crc_errors);
  CHECK(c.commands > 0);
  CHECK(c.malformed_bytes > 0);
  CHECK(c.frames_dropped > 0);
  if (kind == 1) CHECK(c.crc_errors > 0);
}

TEST_CASE("The output resynchronises on stray reply bytes and a port that takes little") {
  const ServoControllerConfig config = Configured(ServoProtocol::kMaestro);
  auto stream = std::make_unique<MemoryStream>();
  MemoryStream& line = *stream;
  ServoOutput out(config, std::move(stream));

  SECTION("bytes with no request outstanding are dropped") {
    line.Put({0x01, 0x02, 0x03});
    out.Update(0.0);  // reads first, then polls
    CHECK(out.counters().unexpected_bytes == 3);
    CHECK(line.out == Bytes{0xA1});
    line.Put({0x20, 0x00});
    out.Update(0.1);
    CHECK(out.counters().error_replies == 1);
    CHECK(out.last_errors() == maestro::kSerialTimeout);
  }
  SECTION("a reply out of step by a byte is shifted back into step") {
    out.Update(0.0);
    line.Put({0x99, 0x08, 0x00});  // junk, then the reply
    out.Update(0.1);
    CHECK(out.counters().error_replies == 1);
    CHECK(out.last_errors() == maestro::kSerialCrcError);
    CHECK(out.counters().unexpected_bytes == 1);
  }
  SECTION("an unanswered poll is given up at the next") {
    out.Update(0.0);
    line.Put({0x08});  // half a reply
    out.Update(0.6);
    CHECK(out.counters().replies_missing == 1);
    CHECK(out.counters().unexpected_bytes == 1);
    line.Put({0x10, 0x00});
    out.Update(0.7);
    CHECK(out.last_errors() == maestro::kSerialProtocolError);
  }
  SECTION("a short write is finished before anything else") {
    line.accept = 10;
    out.Send(SomePulses());  // 28 bytes: 10 taken
    CHECK(out.counters().write_short == 1);
    out.Send(SomePulses(1.0));  // the tail first (10 more): still short, skipped
    CHECK(out.counters().frames_skipped == 1);
    line.accept = SIZE_MAX;
    out.Send(SomePulses(2.0));
    CHECK(out.counters().bytes_sent == 56);
    CHECK(out.counters().frames_sent == 2);
    // The controller sees whole commands only.
    MemorySim m(config);
    m.Feed(line.out);
    CHECK(m.sim->counters().commands == 14);
    CHECK(m.sim->counters().frames_dropped == 0);
    CHECK(m.sim->errors() == 0);
    CHECK(m.sim->pulse_us() == SomePulses(2.0));
  }
}

TEST_CASE(
    "Only error polls going wrong three in a row make the Maestro untrusted; a good one in between "
    "resets") {
  const ServoControllerConfig config = Configured(ServoProtocol::kMaestro);  // polled every 0.5 s
  auto stream = std::make_unique<MemoryStream>();
  MemoryStream& line = *stream;
  ServoOutput out(config, std::move(stream));
  double t = 0.0;
  // One poll window: the reply to the poll that opened it (none: nothing
  // answers), then the next poll, which judges it.
  const auto window = [&](const Bytes& reply) {
    line.Put(reply);
    t += config.error_poll_s;
    out.Update(t);
  };
  out.Update(t);         // the first poll opens the first window
  window({0x08, 0x00});  // a CRC error
  window({});            // no answer
  CHECK(out.polls_wrong_in_a_row() == 2);
  window({0x00, 0x00});  // clean: the run is broken
  CHECK(out.polls_wrong_in_a_row() == 0);
  window({0x20, 0x00});        // a serial timeout
  window({0x00, 0x00, 0x55});  // a clean reply, then a stray byte
  CHECK(out.polls_wrong_in_a_row() == 2);
  CHECK_FALSE(out.untrusted());
  CHECK(out.untrusted_reason().empty());
  window({0x10, 0x00});  // a protocol error: the third in a row
  CHECK(out.untrusted());
  CHECK(out.counters().polls_wrong == 5);
  // The reason names the run that decided, not the CRC error and the
  // missing reply before the good poll.
  CHECK_THAT(
      out.untrusted_reason(),
      Catch::Contains(
          "servo controller on memory cannot be trusted: 3 error polls in a row went wrong "
          "(over 1.5 s)") &&
          Catch::Contains("1 bytes that answer no request") &&
          Catch::Contains("replies carried serial timeout, protocol error (register 0x0030)") &&
          !Catch::Contains("no reply") && !Catch::Contains("CRC"));
  CHECK(out.errors_seen() ==
        (maestro::kSerialCrcError | maestro::kSerialTimeout | maestro::kSerialProtocolError));
  // Untrusted for good: good polls after it change nothing.
  window({0x00, 0x00});
  window({0x00, 0x00});
  CHECK(out.untrusted());
}

TEST_CASE("Send and both Updates allocate nothing") {
  const bool maestro_protocol = GENERATE(true, false);
  const ServoControllerConfig config = Configured(
      maestro_protocol ? ServoProtocol::kMaestro : ServoProtocol::kSc8000, maestro_protocol);
  PtyBench bench(config);
  bench.output->Send(SomePulses());
  bench.output->Update(0.0);
  bench.sim->Update(0.0);
  const uint64_t before = test::ThreadAllocations();
  for (int k = 0; k < 2000; ++k) {
    bench.output->Send(SomePulses(k % 50));
    bench.output->Update(k * 0.01);
    bench.sim->Update(k * 0.01);
  }
  bench.output->GoHome();
  const uint64_t after = test::ThreadAllocations();
  CHECK(after == before);
  CHECK(bench.sim->counters().commands > 0);
}

// --- the port ---------------------------------------------------------------

TEST_CASE("A serial port that vanishes throws SerialLost") {
  SECTION("the pty master closed under a SerialPort") {
    PtyPair pty;
    SerialPort port(pty.slave_path(), 115200);
    const uint8_t byte = 0x42;
    CHECK(port.Write(&byte, 1) == 1);
    uint8_t got = 0;
    REQUIRE(test::WaitFor([&] { return ::read(pty.master_fd(), &got, 1) == 1; }, kWait_s));
    CHECK(got == 0x42);
    uint8_t buffer[8];
    CHECK(port.Read(buffer, sizeof buffer) == 0);  // nothing yet: not lost
    pty.CloseMaster();
    CHECK_THROWS_AS(port.Read(buffer, sizeof buffer), SerialLost);
    CHECK_THROWS_AS(port.Write(&byte, 1), SerialLost);
    CHECK_THROWS_WITH(port.Read(buffer, sizeof buffer), Catch::Contains(pty.slave_path()));
  }
  SECTION("the adapter's output, when the controller's end goes") {
    PtyBench bench(Configured(ServoProtocol::kMaestro));
    bench.output->Send(SomePulses());
    REQUIRE(bench.CommandsReach(0.0, kBlimpChannels));
    bench.sim.reset();  // the master stream closes
    CHECK_THROWS_AS(bench.output->Update(0.0), SerialLost);
    CHECK_THROWS_AS(bench.output->Send(SomePulses()), SerialLost);
  }
  SECTION("a socket whose other end closed") {
    int fds[2];
    REQUIRE(::socketpair(AF_UNIX, SOCK_STREAM, 0, fds) == 0);
    FdStream stream{UniqueFd(fds[0]), "socketpair"};
    UniqueFd other(fds[1]);
    const uint8_t bytes[] = {1, 2, 3};
    CHECK(stream.Write(bytes, 3) == 3);
    uint8_t buffer[8];
    CHECK(stream.Read(buffer, sizeof buffer) == 0);
    other.reset();
    CHECK_THROWS_AS(stream.Read(buffer, sizeof buffer), SerialLost);
    CHECK_THROWS_AS(stream.Write(bytes, 3), SerialLost);  // no SIGPIPE over a socket
  }
}

TEST_CASE("A port that cannot be opened throws SerialUnavailable naming it") {
  const std::string missing = "/dev/haptel-no-such-servo-port";
  CHECK_THROWS_AS(SerialPort(missing, 115200), SerialUnavailable);
  CHECK_THROWS_AS(SerialPort(missing, 115200), cli::InputError);  // exit 2
  const std::string message =
      test::WhatOf<SerialUnavailable>([&] { SerialPort port(missing, 115200); });
  CHECK_THAT(message, Catch::Contains(missing) && Catch::Contains("No such file or directory"));

  PtyPair pty;
  CHECK_THAT(test::WhatOf<SerialUnavailable>([&] { SerialPort port(pty.slave_path(), 12345); }),
             Catch::Contains("baud 12345") && Catch::Contains("115200"));
  CHECK_THAT(test::WhatOf<SerialUnavailable>([&] { SerialPort port("", 9600); }),
             Catch::Contains("--serial-port"));
  const auto file = test::WriteFile(test::ScratchDir("servo-port") / "not-a-tty", "x");
  CHECK_THAT(test::WhatOf<SerialUnavailable>([&] { SerialPort port(file.string(), 9600); }),
             Catch::Contains(file.string()) && Catch::Contains("not a serial port"));
  CHECK(SerialBaudSupported(9600));
  CHECK_FALSE(SerialBaudSupported(1000));
}

TEST_CASE("A pty pair hands its slave to whoever opens the path") {
  PtyPair pty;
  CHECK(pty.slave_path().rfind("/dev/pts/", 0) == 0);
  SerialPort port(pty.slave_path(), 9600);
  pty.CloseSlave();
  CHECK(pty.slave_fd() == -1);
  auto master = pty.TakeMaster();
  CHECK(pty.master_fd() == -1);
  CHECK_THROWS_AS(pty.TakeMaster(), SerialUnavailable);
  const uint8_t out[] = {0x84, 0x00, 0x70, 0x2E};
  CHECK(master->Write(out, 4) == 4);
  Bytes got;
  REQUIRE(test::WaitFor(
      [&] {
        uint8_t b[8];
        const size_t n = port.Read(b, sizeof b);
        got.insert(got.end(), b, b + n);
        return got.size() >= 4;
      },
      kWait_s));
  CHECK(got == Bytes(out, out + 4));  // raw: nothing translated
}
