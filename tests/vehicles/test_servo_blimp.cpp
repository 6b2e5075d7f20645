// The real blimp's adapter (ServoBlimpAdapter) on a pty, against a Maestro
// the test plays on the pty's other end that misbehaves on purpose
// (fake_maestro.hpp): a CRC error at every poll, no answer at all, random
// bytes — each makes the controller untrusted after
// ServoOutput::kUntrustedAfterPolls windows, the state a fault naming the
// errors (the operator's run ends as vehicle lost), and every channel
// neutral whatever is commanded; a single CRC error is shown in the state
// and nothing more. Time is the adapter's dt (a fake clock); waits for
// bytes to cross the pty are bounded, nothing is timed.
#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <string>

#include "fake_maestro.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/config/reality.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/servo/calibration.hpp"
#include "haptel/servo/maestro.hpp"
#include "haptel/servo/serial_port.hpp"
#include "haptel/vehicles/blimp_adapters.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::FakeMaestro;
using Manner = FakeMaestro::Manner;

namespace {

constexpr double kWait_s = 30.0;  // bounds a wait for bytes to cross the pty; asserts no timing
constexpr double kTick_s = 0.02;

/// The real blimp's controller settings (a Maestro with CRC, polled every 0.5 s).
ServoControllerConfig Shipped() {
  const ServoControllerConfig c = LoadVehicle("config/vehicles/blimp-maestro.yaml").servo;
  REQUIRE(c.protocol == ServoProtocol::kMaestro);
  return c;
}

/// The adapter on the pty's slave path, the fake Maestro on its master.
struct Rig {
  servo::PtyPair pty;
  ServoControllerConfig config = Shipped();
  std::unique_ptr<vehicles::ServoBlimpAdapter> adapter;
  std::unique_ptr<FakeMaestro> maestro;

  explicit Rig(Manner manner, ServoControllerConfig with = Shipped()) : config(std::move(with)) {
    adapter = std::make_unique<vehicles::ServoBlimpAdapter>(
        config, std::make_unique<servo::SerialPort>(pty.slave_path(), config.baud));
    maestro = std::make_unique<FakeMaestro>(pty.TakeMaster(), config.crc, manner);
  }

  const servo::ServoOutputCounters& counters() const { return adapter->output().counters(); }

  /// Lets every byte cross both ways: the fake has read all the adapter
  /// sent, and the adapter all the fake sent (replies as replies; random
  /// bytes within one, which may wait as half a reply).
  void Settle(bool random_bytes) {
    const bool settled = test::WaitFor(
        [&] {
          maestro->Update();
          adapter->Update(0.0);  // reads; no time passes, so nothing new is due
          const servo::ServoOutputCounters& c = counters();
          if (maestro->bytes_read() != c.bytes_sent) return false;
          if (!random_bytes)
            return c.error_replies == static_cast<uint64_t>(maestro->replies_sent());
          return 2 * c.error_replies + c.unexpected_bytes + 1 >= maestro->bytes_written();
        },
        kWait_s);
    REQUIRE(settled);
  }

  /// One error-poll window (error_poll_s) of 50 Hz ticks commanding `command`.
  void FlyWindow(const BlimpCommand& command, bool random_bytes = false) {
    const int ticks = static_cast<int>(config.error_poll_s / kTick_s + 0.5);
    for (int i = 0; i < ticks; ++i) {
      adapter->Apply(command);
      adapter->Update(kTick_s);
      Settle(random_bytes);
    }
  }

  /// The pulses on the wire, per channel, as the fake decoded them.
  std::array<double, kBlimpChannels> WirePulses() const {
    std::array<double, kBlimpChannels> out{};
    for (int i = 0; i < kBlimpChannels; ++i)
      out[i] = maestro->output_us(config.channels[i].channel);
    return out;
  }
};

/// Every channel within a quarter µs (the Maestro's resolution) of `want`.
bool Near(const std::array<double, kBlimpChannels>& have,
          const std::array<double, kBlimpChannels>& want) {
  for (size_t i = 0; i < have.size(); ++i) {
    if (std::abs(have[i] - want[i]) > 0.26) return false;
  }
  return true;
}

BlimpCommand Climbing() {
  BlimpCommand c;
  c.power = 0.6;
  c.helix = 0.5;
  c.rudder = -0.3;
  return c;
}

}  // namespace

TEST_CASE(
    "a Maestro that cannot be trusted is a fault naming its errors, and every channel goes "
    "neutral") {
  const Manner manner = GENERATE(Manner::kCrcErrorEveryPoll, Manner::kSilent, Manner::kRandomBytes);
  const bool random_bytes = manner == Manner::kRandomBytes;
  Rig rig(manner);
  const BlimpCommand command = Climbing();
  const auto commanded = servo::PulsesFromCommands(rig.config, vehicles::ChannelValues(command));
  const auto neutral = servo::NeutralPulses(rig.config);

  // Windows go wrong one after the other; the first ones are tolerated.
  int windows = 0;
  while (!rig.adapter->State().fault && windows < 10) {
    rig.FlyWindow(command, random_bytes);
    ++windows;
    if (!rig.adapter->State().fault)
      CHECK(Near(rig.WirePulses(), commanded));  // still flying as told
  }
  INFO("windows flown: " << windows << ", polls answered " << rig.counters().error_replies
                         << ", missing " << rig.counters().replies_missing << ", stray bytes "
                         << rig.counters().unexpected_bytes);
  const vehicles::BlimpAdapterState state = rig.adapter->State();
  REQUIRE(state.fault);
  // Judged at the poll that closed the third wrong window in a row, not before.
  CHECK(rig.counters().polls_wrong ==
        static_cast<uint64_t>(servo::ServoOutput::kUntrustedAfterPolls));
  CHECK(rig.adapter->output().untrusted());

  const std::string& why = state.fault_message;
  CHECK_THAT(
      why, Catch::Contains("servo controller on " + rig.pty.slave_path() + " cannot be trusted") &&
               Catch::Contains("3 error polls in a row went wrong"));
  switch (manner) {
    case Manner::kCrcErrorEveryPoll:
      CHECK_THAT(why, Catch::Contains("CRC error (register 0x0008)"));
      CHECK(state.controller_errors == servo::maestro::kSerialCrcError);
      break;
    case Manner::kSilent:
      CHECK_THAT(why, Catch::Contains("3 of them got no reply"));
      CHECK(rig.counters().replies_missing >= 3);
      break;
    default:
      CHECK_THAT(why, Catch::Contains("bytes that answer no request"));
      CHECK(rig.counters().unexpected_bytes > 0);
      break;
  }

  // Neutral at once, on the wire too, and held whatever is commanded.
  CHECK(state.pulse_us == neutral);
  CHECK(Near(rig.WirePulses(), neutral));
  rig.FlyWindow(command, random_bytes);
  CHECK(rig.adapter->State().fault);
  CHECK(rig.adapter->State().pulse_us == neutral);
  CHECK(rig.adapter->State().applied.power == 0.0);
  CHECK(Near(rig.WirePulses(), neutral));
}

TEST_CASE("a single CRC error from the Maestro is shown in the state and does not end the flight") {
  Rig rig(Manner::kOneCrcError);
  const BlimpCommand command = Climbing();
  const auto commanded = servo::PulsesFromCommands(rig.config, vehicles::ChannelValues(command));
  bool shown = false;
  for (int window = 0; window < 8; ++window) {
    rig.FlyWindow(command);
    shown = shown || rig.adapter->State().controller_errors == servo::maestro::kSerialCrcError;
    REQUIRE_FALSE(rig.adapter->State().fault);
  }
  CHECK(shown);
  CHECK(rig.adapter->output().errors_seen() == servo::maestro::kSerialCrcError);
  CHECK(rig.counters().polls_wrong == 1);
  CHECK_FALSE(rig.adapter->output().untrusted());
  CHECK(rig.adapter->State().fault_message.empty());
  CHECK(Near(rig.WirePulses(), commanded));
  CHECK(rig.adapter->State().controller_errors == 0);  // cleared by the device's next reading
}

TEST_CASE("a healthy Maestro is never judged") {
  Rig rig(Manner::kHealthy);
  for (int window = 0; window < 8; ++window) rig.FlyWindow(Climbing());
  CHECK(rig.counters().polls_wrong == 0);
  CHECK(rig.counters().error_replies >= 8);
  CHECK_FALSE(rig.adapter->State().fault);
}

TEST_CASE(
    "the surveillance camera's pan, tilt and zoom go out on their own outputs; the pilot's camera "
    "stays on its channels; the simulated blimp's controller holds them") {
  const VehicleConfig blimp = LoadVehicle("config/vehicles/sim-blimp-surveillance.yaml");
  const ServoControllerConfig config = blimp.ServoWithCameras();
  REQUIRE(config.camera_channels.size() == 3);
  Rig rig(Manner::kHealthy, config);
  BlimpCommand pilot = Climbing();
  pilot.camera_pan = 0.4;
  const CameraAim aim{.pan = -1.2, .tilt = -0.6, .zoom = 7.5};
  rig.adapter->AimCamera(1, aim);
  rig.FlyWindow(pilot);

  // Each axis's pulse from its own calibration: pan 7, tilt 8, zoom 9.
  for (const CameraServoChannel& axis : config.camera_channels) {
    const double want = servo::PulseFromCommand(axis.output, servo::CameraAxisCommand(axis, aim));
    INFO("output " << axis.output.channel);
    CHECK(std::abs(rig.maestro->output_us(axis.output.channel) - want) <= 0.26);
  }
  // Zoom 7.5 of 1..10 is command 0.44: 1722 µs.
  CHECK(rig.maestro->output_us(9) == Approx(1722.2).margin(0.5));
  // The driving command and the pilot's camera as ever.
  const auto commanded = servo::PulsesFromCommands(config, vehicles::ChannelValues(pilot));
  CHECK(Near(rig.WirePulses(), commanded));

  // Aiming a camera without servos (the pilot's, index 0) moves none of them.
  rig.adapter->AimCamera(0, {.pan = 1.0, .tilt = 0.0, .zoom = 1.0});
  rig.FlyWindow(pilot);
  CHECK(rig.maestro->output_us(9) == Approx(1722.2).margin(0.5));

  // The simulated blimp: the same bytes through its own pty to its
  // simulated Maestro, whose outputs read back are where the camera points.
  vehicles::SimulatedServoBlimp sim(config, blimp.airship, LoadBlimpCourse(blimp.world),
                                    NominalReality(blimp));
  sim.AimCamera(1, aim);
  CameraAim shown;
  const bool reached = test::WaitFor(
      [&] {
        sim.Update(kTick_s);
        return sim.CameraAimed(1, &shown) && std::abs(shown.zoom - aim.zoom) < 0.01;
      },
      kWait_s);
  REQUIRE(reached);
  CHECK(shown.pan == Approx(aim.pan).margin(0.005));
  CHECK(shown.tilt == Approx(aim.tilt).margin(0.005));
  CHECK_FALSE(sim.CameraAimed(0, &shown));  // the pilot's camera: its pan/tilt are the command's
}
