// End to end, the blimp: `haptel run` flies the short hop through DDS with
// the real servo adapter talking Maestro through a pty to the simulated
// controller; and `haptel-vehicle` for the real blimp, on a pty we read as
// the controller would, sends the commanded pulses on all seven channels
// and goes to neutral on its own once the commands stop; and a Maestro that
// starts answering every error poll with a CRC error mid-flight ends the
// run as vehicle lost, naming the error.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>

#include "child.hpp"
#include "fake_maestro.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/record/recorder.hpp"
#include "haptel/servo/calibration.hpp"
#include "haptel/servo/serial_port.hpp"
#include "haptel/servo/sim_servo_controller.hpp"
#include "haptel/vehicles/blimp_adapters.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::FinishedJson;
using haptel::test::JsonField;
using haptel::test::Output;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// Every channel within a quarter µs (the Maestro's resolution) of `want`.
bool PulsesAre(const std::array<double, kBlimpChannels>& have,
               const std::array<double, kBlimpChannels>& want) {
  for (size_t i = 0; i < have.size(); ++i) {
    if (std::abs(have[i] - want[i]) > 0.26) return false;
  }
  return true;
}

}  // namespace

// The two hops fly side by side (each about a minute of real time: a blimp
// does not step in simulated time), each on its own domain and database.
TEST_CASE(
    "blimp hops over DDS: through the Maestro adapter and a pty, completed, the JSON and the "
    "database name the vehicle and the interface; at 400 ms each way, the pilot flying the "
    "predicted blimp, completed, prediction and its error recorded") {
  const auto dir = test::ScratchDir("e2e-blimp");
  const auto db = dir / "runs.db";
  const auto predict_db = dir / "predict-runs.db";
  auto hops = test::StartAll(
      {{Bin("haptel"), "run", "--config", "config/blimp.yaml", "--vehicle",
        "config/vehicles/sim-blimp-maestro.yaml", "--track", "config/tracks/blimp-hop.yaml",
        "--json", "--quiet", "--domain", std::to_string(test::UniqueDomain(71)), "--database",
        db.string(), "--vehicle-timeout", "5", "--reality", "none"},
       {Bin("haptel"),
        "run",
        "--config",
        "config/blimp.yaml",
        "--track",
        "config/tracks/blimp-hop.yaml",
        "--link-fault",
        "delay=400ms",
        "--predict",
        "on",
        "--json",
        "--quiet",
        "--domain",
        std::to_string(test::UniqueDomain(77)),
        "--database",
        predict_db.string(),
        "--vehicle-timeout",
        "5",
        "--reality",
        "none"}});
  {
    Child& haptel = *hops[0];
    const std::string json = FinishedJson(haptel, 300.0);
    INFO(Output(haptel));
    CHECK(JsonField(json, "outcome") == "completed");
    CHECK(JsonField(json, "completed") == "true");
    CHECK(JsonField(json, "gates_total") == "1");
    CHECK(JsonField(json, "gates_passed") == "1");
    CHECK(JsonField(json, "vehicle_kind") == "servo-blimp-sim");
    CHECK(JsonField(json, "interface") == "blimp-gesture");
    CHECK(JsonField(json, "track") == "blimp-hop");
    CHECK(std::stod(JsonField(json, "lap_time_s")) > 5.0);
    CHECK(std::stod(JsonField(json, "command_rtt_ms_p50")) > 0.0);
    // The blimp's predictor runs with the display off too: the pilot saw the
    // states as they came, and the model's error against them is recorded
    // (the airship model of the vehicle file behind the Maestro's pulses; the
    // twin, --reality none, flies that very model).
    CHECK(JsonField(json, "predict") == "false");
    REQUIRE(JsonField(json, "prediction_error_m_p95") != "null");
    CHECK(std::stod(JsonField(json, "prediction_error_m_p95")) < 0.1);

    record::Recorder recorder(db);
    const auto runs = recorder.LoadAll();
    REQUIRE(runs.size() == 1);
    CHECK(runs[0].completed);
    CHECK(runs[0].outcome == "completed");
    CHECK(runs[0].vehicle_kind == "servo-blimp-sim");
    CHECK(runs[0].interface == "blimp-gesture");
    CHECK(runs[0].track == "blimp-hop");
    CHECK(runs[0].controller_errors == 0);  // a servo controller, and no error from it
    CHECK(runs[0].prediction_error_m_p95 >= 0.0);
    REQUIRE(runs[0].splits.size() == 1);
    CHECK(runs[0].splits[0].passed);
    CHECK_FALSE(runs[0].path.empty());
  }
  {  // 400 ms each way, the pilot flying the predicted blimp.
    Child& haptel = *hops[1];
    const std::string json = FinishedJson(haptel, 300.0);
    INFO(Output(haptel));
    CHECK(JsonField(json, "outcome") == "completed");
    CHECK(JsonField(json, "gates_passed") == "1");
    CHECK(JsonField(json, "predict") == "true");
    CHECK(std::stod(JsonField(json, "command_rtt_ms_p50")) > 700.0);
    // The model is the simulated blimp's own (the twin, --reality none):
    // centimetres at most, where the delayed state is metres behind.
    REQUIRE(JsonField(json, "prediction_error_m_p95") != "null");
    CHECK(std::stod(JsonField(json, "prediction_error_m_p95")) < 0.1);

    record::Recorder recorder(predict_db);
    const auto runs = recorder.LoadAll();
    REQUIRE(runs.size() == 1);
    CHECK(runs[0].predict);
    CHECK(runs[0].link_fault == JsonField(json, "link_fault"));
    CHECK(runs[0].prediction_error_m_p95 >= 0.0);
  }
}

TEST_CASE(
    "haptel-vehicle on a pty: the commanded pulses on all seven channels, then neutral from its "
    "own "
    "watchdog once the commands stop") {
  const VehicleConfig config = LoadVehicle("config/vehicles/blimp-maestro.yaml");
  REQUIRE(config.servo.protocol == ServoProtocol::kMaestro);
  REQUIRE(config.servo.crc);
  // The controller's own timeout out of the way: only the node's watchdog
  // can bring the neutral pulses back.
  ServoControllerConfig controller_config = config.servo;
  controller_config.controller_timeout_s = 60.0;
  servo::PtyPair pty;
  servo::SimServoController controller(controller_config, pty.TakeMaster());
  const std::array<double, kBlimpChannels> neutral = servo::NeutralPulses(config.servo);

  const int domain = test::UniqueDomain(73);
  const std::string name = "blimp-e2e";
  Child vehicle({Bin("haptel-vehicle"), "--config", "config/vehicles/blimp-maestro.yaml",
                 "--serial-port", pty.slave_path(), "--domain", std::to_string(domain), "--name",
                 name});
  LinkConfig link = config.link;
  link.domain_id = domain;
  link::Participant participant(link, "test-operator");
  link::BlimpCommandWriter commands(participant, link::TopicName(name, "command"),
                                    link::Profile::kCommand);

  const auto now_s = [] { return NsToS(MonotonicNs()); };
  const auto pump_until = [&](double timeout_s, const auto& done) {
    const double until = now_s() + timeout_s;
    while (now_s() < until) {
      controller.Update(now_s());
      vehicle.Pump();
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
  };
  INFO("vehicle stderr:\n" << vehicle.err());

  // Before any command: valid frames, every channel at neutral.
  REQUIRE(pump_until(20.0, [&] { return controller.counters().commands >= 7; }));
  CHECK(PulsesAre(controller.pulse_us(), neutral));

  // Commands at 50 Hz: every channel where the calibration puts it.
  BlimpCommand c;
  c.elevator = 0.5;
  c.rudder = -0.5;
  c.power = 0.6;
  c.helix = 0.25;
  c.tail_rotor = 0.0;  // with power on, the cockpit never turns the tail rotor
  c.camera_pan = 0.5;
  c.camera_tilt = -0.3;
  const std::array<double, kBlimpChannels> commanded =
      servo::PulsesFromCommands(config.servo, vehicles::ChannelValues(c));
  msg::BlimpCommand m;
  uint64_t seq = 0;
  double last_sent_s = 0.0;
  bool reached = false;
  const double until = now_s() + 10.0;
  double sent_after_reached_until = 0.0;
  while (now_s() < until) {
    m.seq(++seq);
    m.sent_ns(MonotonicNs());
    m.elevator(static_cast<float>(c.elevator));
    m.rudder(static_cast<float>(c.rudder));
    m.power(static_cast<float>(c.power));
    m.helix(static_cast<float>(c.helix));
    m.tail_rotor(static_cast<float>(c.tail_rotor));
    m.camera_pan(static_cast<float>(c.camera_pan));
    m.camera_tilt(static_cast<float>(c.camera_tilt));
    commands.Write(m);
    last_sent_s = now_s();
    pump_until(0.02, [] { return false; });
    if (!reached && PulsesAre(controller.pulse_us(), commanded)) {
      reached = true;
      sent_after_reached_until = now_s() + 1.0;  // a second more of steady commands
    }
    if (reached && now_s() > sent_after_reached_until) break;
  }
  INFO("pulses: " << controller.pulse_us()[0] << " " << controller.pulse_us()[1] << " "
                  << controller.pulse_us()[2] << " " << controller.pulse_us()[3] << " "
                  << controller.pulse_us()[4] << " " << controller.pulse_us()[5] << " "
                  << controller.pulse_us()[6]);
  REQUIRE(reached);
  CHECK(PulsesAre(controller.pulse_us(), commanded));  // held while the commands come
  CHECK(controller.pulse_us()[5] < neutral[5]);        // pan is reversed on this blimp

  // The commands stop: the node's watchdog sends every channel to neutral.
  REQUIRE(pump_until(5.0, [&] { return PulsesAre(controller.pulse_us(), neutral); }));
  const double neutral_after_s = now_s() - last_sent_s;
  std::printf(
      "haptel-vehicle on a pty: neutral pulses %.0f ms after the last command (watchdog %.0f ms)\n",
      neutral_after_s * 1e3, config.watchdog_timeout_s * 1e3);
  // The node's watchdog (0.2 s), not the controller's (60 s here): the
  // time on the wire is measured and printed, not asserted (a loaded
  // machine adds latency).
  CHECK(controller.counters().timeouts == 0);
  CHECK_FALSE(controller.timed_out());

  // Every byte decoded as the Maestro would: no CRC errors, nothing dropped.
  CHECK(controller.counters().crc_errors == 0);
  CHECK(controller.counters().malformed_bytes == 0);
  CHECK(controller.counters().frames_dropped == 0);
  CHECK(controller.errors() == 0);
  CHECK(controller.counters().commands > 100);

  const std::string ended = vehicle.Terminate(5.0);
  CHECK(ended == "exited with code 0");
}

TEST_CASE(
    "a Maestro that starts reporting a CRC error at every poll mid-flight ends the run as vehicle "
    "lost, "
    "naming the error; the vehicle holds neutral") {
  const VehicleConfig config = LoadVehicle("config/vehicles/blimp-maestro.yaml");
  REQUIRE(config.servo.crc);
  servo::PtyPair pty;
  test::FakeMaestro maestro(pty.TakeMaster(), config.servo.crc,
                            test::FakeMaestro::Manner::kHealthy);
  const int domain = test::UniqueDomain(75);
  const std::string name = "blimp-crc";
  const auto dir = test::ScratchDir("e2e-blimp-crc");
  Child vehicle({Bin("haptel-vehicle"), "--config", "config/vehicles/blimp-maestro.yaml",
                 "--serial-port", pty.slave_path(), "--domain", std::to_string(domain), "--name",
                 name});
  const auto pump_until = [&](double timeout_s, const auto& done) {
    return test::WaitFor(
        [&] {
          maestro.Update();
          vehicle.Pump();
          return done();
        },
        timeout_s);
  };
  REQUIRE(
      pump_until(30.0, [&] { return vehicle.err().find(" up on domain") != std::string::npos; }));

  Child run({Bin("haptel"),
             "run",
             "--config",
             "config/blimp.yaml",
             "--attach",
             "--vehicle",
             "config/vehicles/blimp-maestro.yaml",
             "--vehicle-name",
             name,
             "--track",
             "config/tracks/blimp-hop.yaml",
             "--operator",
             "auto",
             "--view",
             "none",
             "--json",
             "--domain",
             std::to_string(domain),
             "--database",
             (dir / "runs.db").string(),
             "--vehicle-timeout",
             "5"});
  // The flight is under way (its first progress line), and the controller healthy until now.
  REQUIRE(pump_until(60.0, [&] {
    run.Pump();
    return run.err().find(" blimp  lap ") != std::string::npos;
  }));
  REQUIRE(vehicle.err().find("stopped itself") == std::string::npos);
  maestro.set_manner(test::FakeMaestro::Manner::kCrcErrorEveryPoll);
  REQUIRE(pump_until(60.0, [&] { return !run.Alive(); }));
  run.Wait(5.0);
  vehicle.Pump();
  INFO("run stdout:\n"
       << run.out() << "\nrun stderr:\n"
       << run.err() << "\nvehicle stderr:\n"
       << vehicle.err());
  CHECK(run.ExitDescription() == "exited with code 3");
  const std::string json = run.LastLine();
  REQUIRE(json.front() == '{');
  CHECK(JsonField(json, "outcome") == "vehicle lost");
  CHECK_THAT(JsonField(json, "message"),
             Catch::Contains("vehicle '" + name + "' stopped itself: servo controller on " +
                             pty.slave_path() + " cannot be trusted") &&
                 Catch::Contains("CRC error (register 0x0008)"));
  CHECK(JsonField(json, "controller_errors") == "8");
  {  // and the database keeps them beside the run
    record::Recorder recorder(dir / "runs.db");
    const auto runs = recorder.LoadAll();
    REQUIRE(runs.size() == 1);
    CHECK(runs[0].controller_errors == 8);
  }
  CHECK_THAT(run.out(), Catch::Contains("servo controller errors: CRC error (register 0x0008)"));
  // The vehicle says so too, and holds every channel at neutral whatever came.
  REQUIRE(pump_until(
      10.0, [&] { return vehicle.err().find("the vehicle stopped itself") != std::string::npos; }));
  const std::array<double, kBlimpChannels> neutral = servo::NeutralPulses(config.servo);
  std::array<double, kBlimpChannels> wire{};
  for (int i = 0; i < kBlimpChannels; ++i)
    wire[i] = maestro.output_us(config.servo.channels[i].channel);
  CHECK(PulsesAre(wire, neutral));
  CHECK(vehicle.Terminate(5.0) == "exited with code 0");
}

TEST_CASE(
    "the pilot's head: --head openxr with no OpenXR runtime says so and the mouse turns the "
    "camera, the JSON names the head; a head the run cannot have is refused") {
  const auto dir = test::ScratchDir("e2e-blimp-head");
  // No runtime, whatever this machine has: a runtime file that is not there.
  setenv("XR_RUNTIME_JSON", "/nonexistent/haptel-test-openxr-runtime.json", 1);
  // A person at a game controller (none plugged in): the run waits for it until its time limit.
  Child haptel({Bin("haptel"),
                "run",
                "--config",
                "config/blimp.yaml",
                "--track",
                "config/tracks/blimp-hop.yaml",
                "--interface",
                "blimp-gamepad",
                "--operator",
                "person",
                "--view",
                "none",
                "--head",
                "openxr",
                "--time-limit",
                "1",
                "--json",
                "--domain",
                std::to_string(test::UniqueDomain(79)),
                "--database",
                (dir / "runs.db").string(),
                "--reality",
                "none"});
  // Refused before anything starts: the stick that flies cannot also look, and a robot's
  // camera does not turn.
  Child both({Bin("haptel"), "run", "--config", "config/blimp.yaml", "--interface", "blimp-gamepad",
              "--operator", "person", "--view", "none", "--head", "gamepad", "--database",
              (dir / "refused.db").string()});
  Child robot({Bin("haptel"), "run", "--operator", "auto", "--view", "none", "--head", "gamepad",
               "--database", (dir / "refused.db").string()});
  const int code = haptel.Wait(120.0);
  unsetenv("XR_RUNTIME_JSON");
  INFO("stdout:\n" << haptel.out() << "\nstderr:\n" << haptel.err());
  CHECK(code == 1);  // the time limit
  const std::string line =
      "no OpenXR runtime (XR_ERROR_RUNTIME_UNAVAILABLE): head follows the mouse";
  CHECK(haptel.err().find(line) != std::string::npos);
  const std::string json = haptel.LastLine();
  REQUIRE(json.front() == '{');
  CHECK(JsonField(json, "outcome") == "time limit");
  CHECK(JsonField(json, "head_source") == "mouse");
  CHECK(JsonField(json, "head_fallback") == line);

  CHECK(both.Wait(60.0) != 0);
  INFO(both.err());
  CHECK(both.err().find("option --head gamepad: interface 'blimp-gamepad' flies with the "
                        "controller's right stick") != std::string::npos);
  CHECK(robot.Wait(60.0) != 0);
  INFO(robot.err());
  CHECK(robot.err().find("has no camera the head turns") != std::string::npos);
}
