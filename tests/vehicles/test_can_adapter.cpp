// The CAN robot's adapter against hand-computed bytes and a far end driven
// by the test through a socket pair: start-up, velocity set-points, silent
// nodes, axis errors, error frames, bus-off, the watchdog stop, replay of a
// recorded log, and a fuzz run of the decoder.
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <vector>

#include "haptel/vehicles/can_robot.hpp"
#include "haptel/vehicles/odrive_can.hpp"
#include "haptel/vehicles/sim_can_robot.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::vehicles;

namespace {

std::vector<uint8_t> Bytes(const can_frame& f) { return {f.data, f.data + f.can_dlc}; }

VehicleConfig CanConfigured() {
  VehicleConfig c;
  c.kind = "can-robot-sim";
  return c;  // defaults: nodes 1, 2, 3; heartbeat 0.03 s; 100 Hz; right reversed
}

/// A CanRobot and the far end of its bus, which the test plays.
struct Bench {
  std::unique_ptr<CanBus> far;
  std::unique_ptr<CanRobot> robot;
  Bench() {
    auto [near, other] = MakeSocketPairBus();
    far = std::move(other);
    robot = std::make_unique<CanRobot>(std::move(near), CanConfigured());
  }
  /// Every frame the robot sent since the last call.
  std::vector<can_frame> Sent() {
    std::vector<can_frame> frames;
    can_frame f{};
    while (far->Receive(f)) frames.push_back(f);
    return frames;
  }
  /// The three nodes' heartbeats (healthy unless told), then one step.
  void Beat(double dt, bool left = true, bool right = true, uint32_t left_error = 0) {
    if (left) far->Send(odrive::Heartbeat(1, left_error, odrive::kClosedLoop));
    if (right) far->Send(odrive::Heartbeat(2, 0, odrive::kClosedLoop));
    far->Send(io_node::Heartbeat(3, io_node::kOperational));
    robot->Update(dt);
  }
};

float VelocityOf(const can_frame& f) { return odrive::DecodeSetInputVel(f)->turns_per_s; }

/// The last velocity set-point sent to `node` among `frames` (NaN: none).
float LastVelocity(const std::vector<can_frame>& frames, int node) {
  float v = std::nanf("");
  for (const can_frame& f : frames) {
    if (f.can_id == odrive::Id(node, odrive::kSetInputVel)) v = VelocityOf(f);
  }
  return v;
}

int Count(const std::vector<can_frame>& frames, uint32_t id) {
  int n = 0;
  for (const can_frame& f : frames) n += f.can_id == id ? 1 : 0;
  return n;
}

}  // namespace

TEST_CASE("CAN Simple frames are the bytes the ODrive documentation gives") {
  CHECK(FormatCandumpFrame(odrive::SetInputVel(1, 1.5F)) == "02D#0000C03F00000000");
  CHECK(FormatCandumpFrame(odrive::SetAxisState(2, odrive::kClosedLoop)) == "047#08000000");
  CHECK(FormatCandumpFrame(odrive::SetControllerMode(1, 2, 2)) == "02B#0200000002000000");
  CHECK(FormatCandumpFrame(odrive::Estop(1)) == "022#");
  CHECK(FormatCandumpFrame(odrive::ClearErrors(2)) == "058#");
  CHECK(FormatCandumpFrame(odrive::Heartbeat(1, 0x40, 8)) == "021#4000000008000000");
  CHECK(FormatCandumpFrame(odrive::EncoderEstimates(2, 1.0F, -0.5F)) == "049#0000803F000000BF");
  CHECK(FormatCandumpFrame(io_node::Inputs(3, true, false, 7)) == "07E#0107");
  CHECK(FormatCandumpFrame(io_node::Heartbeat(3, 1)) == "061#0100");
  // Decoded back; refused with a reason when short or not finite.
  CHECK(odrive::DecodeHeartbeat(odrive::Heartbeat(1, 0x40, 8))->axis_error == 0x40);
  CHECK(odrive::DecodeEncoderEstimates(odrive::EncoderEstimates(2, 1.0F, -0.5F))
            ->velocity_turns_per_s == -0.5F);
  std::string why;
  can_frame short_beat = odrive::Heartbeat(1, 0, 8);
  short_beat.can_dlc = 3;
  CHECK_FALSE(odrive::DecodeHeartbeat(short_beat, &why));
  CHECK(why == "length 3, expected 8");
  CHECK_FALSE(odrive::DecodeSetInputVel(odrive::SetInputVel(1, std::nanf("")), &why));
  CHECK(why == "non-finite velocity");
  CHECK(odrive::DescribeAxisError(0x40 | 0x100) == "MOTOR_FAILED | ENCODER_FAILED");
  CHECK(odrive::DescribeAxisError(0) == "none");
  CHECK(odrive::DescribeAxisError(0x4) == "0x4");
}

TEST_CASE("candump -L lines round-trip, error frames with their flag, garbage refused") {
  can_frame f{};
  REQUIRE(ParseCandumpFrame("02D#0000C03F00000000", f));
  CHECK(f.can_id == 0x02D);
  CHECK(f.can_dlc == 8);
  CHECK(Bytes(f) == Bytes(odrive::SetInputVel(1, 1.5F)));
  can_frame bus_off{};
  bus_off.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  bus_off.can_dlc = 8;
  CHECK(FormatCandumpFrame(bus_off) == "20000040#0000000000000000");
  REQUIRE(ParseCandumpFrame("20000040#0000000000000000", f));
  CHECK(f.can_id == (CAN_ERR_FLAG | CAN_ERR_BUSOFF));
  for (const char* bad : {"xyz", "02D#0", "02D#GG", "02D#000000000000000000", "2D#00", "800#00"}) {
    INFO(bad);
    CHECK_FALSE(ParseCandumpFrame(bad, f));
  }
}

TEST_CASE("SocketCAN on a kernel without CAN support says so, errno 97") {
  const int probe = socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (probe >= 0) {
    close(probe);
    WARN("this kernel has CAN support: nothing to refuse");
    return;
  }
  CHECK_THROWS_WITH(SocketCanBus("can0"), Catch::Contains("can0") && Catch::Contains("errno 97") &&
                                              Catch::Contains("no CAN support"));
}

TEST_CASE("the adapter starts both axes in velocity control and sends set-points at 100 Hz") {
  Bench b;
  b.Beat(0.01);
  const std::vector<can_frame> start = b.Sent();
  CHECK(Count(start, odrive::Id(1, odrive::kSetControllerMode)) == 1);
  CHECK(Count(start, odrive::Id(2, odrive::kSetControllerMode)) == 1);
  CHECK(Count(start, odrive::Id(1, odrive::kSetAxisState)) == 1);
  CHECK(odrive::DecodeControllerMode(start[0])->control_mode == odrive::kControlModeVelocity);
  CHECK(odrive::DecodeControllerMode(start[0])->input_mode == odrive::kInputModeVelRamp);
  b.robot->SetMotors({8, -3});
  for (int i = 0; i < 100; ++i) b.Beat(0.01);
  const std::vector<can_frame> driving = b.Sent();
  CHECK(Count(driving, odrive::Id(1, odrive::kSetInputVel)) == Approx(100).margin(2));
  CHECK(LastVelocity(driving, 1) == Approx(1.6));
  CHECK(LastVelocity(driving, 2) == Approx(0.6));  // level −3 backwards, on the mirrored motor
  CHECK_FALSE(b.robot->State().fault);
  CHECK(b.robot->counters().heartbeats == 303);  // the first step's three, then 100 steps of three
}

TEST_CASE("a silent node stops the robot within 3 heartbeat periods, until errors are cleared") {
  Bench b;
  b.robot->SetMotors({8, 8});
  for (int i = 0; i < 20; ++i) b.Beat(0.01);
  b.Sent();
  double t = 0.0;
  while (!b.robot->State().fault && t < 1.0) {
    b.Beat(0.005, true, false);  // node 2 silent
    t += 0.005;
  }
  CHECK(t <= 0.1);
  CHECK(b.robot->State().fault_message.find("right wheel (node 2) silent") != std::string::npos);
  const std::vector<can_frame> stop = b.Sent();
  CHECK(LastVelocity(stop, 1) == 0.0F);
  CHECK(LastVelocity(stop, 2) == 0.0F);
  CHECK(Count(stop, odrive::Id(1, odrive::kSetAxisState)) == 1);
  // Commands change nothing while the fault stands.
  b.robot->SetMotors({8, 8});
  for (int i = 0; i < 10; ++i) b.Beat(0.01);
  CHECK(Count(b.Sent(), odrive::Id(1, odrive::kSetInputVel)) == 0);
  CHECK(b.robot->State().applied.left == 0);
  b.robot->ClearErrors();
  const std::vector<can_frame> cleared = b.Sent();
  CHECK(Count(cleared, odrive::Id(1, odrive::kClearErrors)) == 1);
  CHECK(Count(cleared, odrive::Id(2, odrive::kClearErrors)) == 1);
  CHECK_FALSE(b.robot->State().fault);
}

TEST_CASE("an axis error stops the robot at once, decoded; clear-errors is never sent unasked") {
  Bench b;
  b.robot->SetMotors({5, 5});
  for (int i = 0; i < 10; ++i) b.Beat(0.01);
  b.Sent();
  b.Beat(0.01, true, true, odrive::kErrorMotorFailed);
  const AdapterState s = b.robot->State();
  REQUIRE(s.fault);
  CHECK(s.fault_message ==
        "left wheel (ODrive node 1) reports axis error MOTOR_FAILED; robot stopped");
  CHECK(b.robot->counters().faults == 1);
  const std::vector<can_frame> after = b.Sent();
  CHECK(LastVelocity(after, 1) == 0.0F);
  for (int i = 0; i < 50; ++i) b.Beat(0.01, true, true, odrive::kErrorMotorFailed);
  const std::vector<can_frame> later = b.Sent();
  CHECK(Count(later, odrive::Id(1, odrive::kClearErrors)) == 0);
  CHECK(Count(later, odrive::Id(2, odrive::kClearErrors)) == 0);
  CHECK(b.robot->counters().faults == 1);
}

TEST_CASE("error frames are counted; bus-off stops the robot") {
  Bench b;
  b.robot->SetMotors({4, 4});
  b.Beat(0.01);
  can_frame e{};
  e.can_id = CAN_ERR_FLAG | CAN_ERR_CRTL;
  e.can_dlc = 8;
  e.data[1] = CAN_ERR_CRTL_RX_PASSIVE;
  b.far->Send(e);
  e = {};
  e.can_id = CAN_ERR_FLAG | CAN_ERR_RESTARTED;
  e.can_dlc = 8;
  b.far->Send(e);
  b.Beat(0.01);
  CHECK(b.robot->counters().error_passive == 1);
  CHECK(b.robot->counters().restarted == 1);
  CHECK_FALSE(b.robot->State().fault);
  e = {};
  e.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  e.can_dlc = 8;
  b.far->Send(e);
  b.Beat(0.01);
  CHECK(b.robot->counters().bus_off == 1);
  CHECK(b.robot->counters().error_frames == 3);
  REQUIRE(b.robot->State().fault);
  CHECK(b.robot->State().fault_message.find("bus-off") != std::string::npos);
}

TEST_CASE("the watchdog's stop sends zero velocity, then idle; the next command drives again") {
  Bench b;
  b.robot->SetMotors({8, 8});
  for (int i = 0; i < 10; ++i) b.Beat(0.01);
  b.Sent();
  b.robot->Stop();
  std::vector<can_frame> stop = b.Sent();
  REQUIRE(stop.size() == 4);
  CHECK(VelocityOf(stop[0]) == 0.0F);
  CHECK(VelocityOf(stop[1]) == 0.0F);
  CHECK(*odrive::DecodeAxisState(stop[2]) == odrive::kIdle);
  CHECK(*odrive::DecodeAxisState(stop[3]) == odrive::kIdle);
  b.robot->Stop();  // again: nothing more to say
  for (int i = 0; i < 5; ++i) b.Beat(0.01);
  CHECK(b.Sent().empty());
  b.robot->SetMotors({4, 4});
  b.Beat(0.01);
  const std::vector<can_frame> again = b.Sent();
  CHECK(Count(again, odrive::Id(1, odrive::kSetAxisState)) == 1);
  CHECK(LastVelocity(again, 1) == Approx(0.8));
}

TEST_CASE("malformed and unknown frames are counted and change nothing") {
  Bench b;
  b.Beat(0.01);
  can_frame short_beat = odrive::Heartbeat(1, odrive::kErrorMotorFailed, 8);
  short_beat.can_dlc = 5;
  b.robot->Decode(short_beat);
  b.robot->Decode(odrive::EncoderEstimates(1, 0.0F, std::nanf("")));
  uint8_t data[2] = {0xFF, 0};
  b.robot->Decode(MakeFrame(odrive::Id(3, io_node::kInputs), data, 2));  // unknown input bits
  b.robot->Decode(MakeFrame(0x7FF, nullptr, 0));
  b.robot->Decode(MakeFrame(odrive::Id(9, odrive::kHeartbeat), nullptr, 8));
  CHECK(b.robot->counters().malformed == 3);
  CHECK(b.robot->counters().unknown == 2);
  CHECK_FALSE(b.robot->State().fault);
  CHECK(b.robot->State().speed == 0.0);
  CHECK_FALSE(b.robot->State().bumper_left);
}

TEST_CASE("a recorded log replayed into the decoder gives the state it recorded") {
  const auto dir = test::ScratchDir("can-replay");
  const auto file = dir / "robot1.log";
  {
    CandumpWriter log(file, "can0");
    int64_t t = 1'795'503'326'000'000'000;
    for (const can_frame& f :
         {odrive::Heartbeat(1, 0, 8), odrive::Heartbeat(2, 0, 8), io_node::Heartbeat(3, 1),
          io_node::Inputs(3, true, false, 1), odrive::EncoderEstimates(1, 3.0F, 1.0F),
          odrive::EncoderEstimates(2, -3.0F, -1.0F)}) {
      log.Write(f, t += 1'000'000);
    }
  }
  size_t malformed = 9;
  const std::vector<LoggedFrame> frames = ReadCandumpLog(file, &malformed);
  REQUIRE(frames.size() == 6);
  CHECK(malformed == 0);
  CHECK(frames[1].t_s == Approx(1795503326.002).epsilon(1e-12));
  CanRobot robot(MakeSocketPairBus().first, CanConfigured());
  for (const LoggedFrame& f : frames) robot.Decode(f.frame);
  const AdapterState s = robot.State();
  CHECK(s.bumper_left);
  CHECK_FALSE(s.bumper_right);
  CHECK(s.speed == Approx(0.1885));  // both wheels forward (the right one mirrored)
  CHECK(s.yaw_rate == Approx(0.0).margin(1e-9));
  CHECK(robot.axis_state(0) == odrive::kClosedLoop);
  CHECK_FALSE(s.fault);
}

TEST_CASE("a million random frames through the decoder: no crash, state stays finite") {
  CanRobot robot(MakeSocketPairBus().first, CanConfigured());
  std::mt19937_64 random(2026);
  const auto start = std::chrono::steady_clock::now();
  constexpr int kFrames = 1'000'000;
  for (int i = 0; i < kFrames; ++i) {
    can_frame f{};
    const uint64_t r = random();
    f.can_id = static_cast<uint32_t>(r & 0x7FF);
    if ((r >> 11) % 16 == 0)
      f.can_id |= CAN_ERR_FLAG | static_cast<uint32_t>((r >> 16) & CAN_ERR_MASK);
    if ((r >> 11) % 16 == 1) f.can_id |= CAN_RTR_FLAG;
    if ((r >> 11) % 16 == 2) f.can_id |= CAN_EFF_FLAG;
    f.can_dlc = static_cast<uint8_t>((r >> 40) % 9);
    const uint64_t bytes = random();
    std::memcpy(f.data, &bytes, 8);
    robot.Decode(f);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "CAN decoder fuzz: %d frames in %.3f s (%.0f frames/s); %llu malformed, %llu unknown, %llu "
      "error frames\n",
      kFrames, seconds, kFrames / seconds,
      static_cast<unsigned long long>(robot.counters().malformed),
      static_cast<unsigned long long>(robot.counters().unknown),
      static_cast<unsigned long long>(robot.counters().error_frames));
  CHECK(robot.counters().received == static_cast<uint64_t>(kFrames));
  CHECK(std::isfinite(robot.State().speed));
  CHECK(std::isfinite(robot.State().yaw_rate));
}

TEST_CASE("the simulated CAN robot drives through the bus, and stops itself on an injected fault") {
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  VehicleConfig config = CanConfigured();
  SimulatedCanRobot sim(track, config);
  const AdapterState before = sim.State();
  sim.SetMotors({8, 8});
  for (int i = 0; i < 200; ++i) sim.Update(0.005);
  CHECK(sim.nodes().axis_state(0) == odrive::kClosedLoop);
  CHECK(sim.nodes().axis_state(1) == odrive::kClosedLoop);
  CHECK(sim.State().speed > 0.1);
  CHECK(std::hypot(sim.State().x - before.x, sim.State().y - before.y) > 0.03);
  CHECK_FALSE(sim.State().fault);
  sim.nodes().InjectAxisError(1, odrive::kErrorControllerFailed);
  double t = 0.0;
  while (!sim.State().fault && t < 1.0) {
    sim.Update(0.005);
    t += 0.005;
  }
  CHECK(t <= 0.1);
  CHECK(sim.State().fault_message.find("CONTROLLER_FAILED") != std::string::npos);
  for (int i = 0; i < 100; ++i) sim.Update(0.005);
  CHECK(std::abs(sim.robot().State().speed) < 0.02);  // stopped within a further 0.5 s
}

TEST_CASE("a stalled control tick does not read as the simulated nodes' silence") {
  // A loaded host's tick half a second late: the nodes are simulated in the
  // same tick, so their heartbeats of that half second are on the bus too
  // (a real bus queues them); in one piece the adapter counted it silence.
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  SimulatedCanRobot sim(track, CanConfigured());
  sim.SetMotors({8, 8});
  for (int i = 0; i < 100; ++i) sim.Update(0.005);
  REQUIRE_FALSE(sim.State().fault);
  const double x0 = sim.robot().State().x, y0 = sim.robot().State().y;
  sim.Update(0.5);
  INFO(sim.State().fault_message);
  CHECK_FALSE(sim.State().fault);
  CHECK(std::hypot(sim.robot().State().x - x0, sim.robot().State().y - y0) > 0.05);  // drove on
}

TEST_CASE(
    "the CAN robot's log on a full disk (/dev/full): its log status reports it and the robot "
    "drives on") {
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  SimulatedCanRobot sim(track, CanConfigured(),
                        std::make_unique<CandumpWriter>("/dev/full", "can0"));
  CHECK(sim.adapter().log_status().path == "/dev/full");
  CHECK(sim.adapter().log_status().error.empty());
  sim.SetMotors({8, 8});
  for (int i = 0; i < 200; ++i)
    sim.Update(0.005);  // a second of bus traffic: several hundred frames
  const CanLogStatus log = sim.adapter().log_status();
  INFO(log.error);
  CHECK(log.error.find("cannot write /dev/full: " + std::string(std::strerror(ENOSPC))) !=
        std::string::npos);
  CHECK(log.frames == 0);
  CHECK(log.frames_lost > CandumpWriter::kFlushEvery);
  CHECK_FALSE(sim.State().fault);  // the log's end does not stop the robot
  CHECK(sim.State().speed > 0.1);
}
