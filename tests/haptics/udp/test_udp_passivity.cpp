// Protocol version 2 and the two-port passivity controller across the UDP
// device: the energy reports on the wire, the arm's end in udp::ArmServer on
// a hand-computed sequence, loss and reordering of the reports, v1/v2
// interop, malformed reports counted and dropped, and the servo loop's tick
// on the v2 path allocating nothing.
//
// Everything runs in one thread on a step clock: a wait for a reply first
// lets the in-process server handle what was sent (loopback delivers at
// once), so each sequence is exact however loaded the machine is.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <vector>

#include "../scripted_device.hpp"
#include "alloc_counter.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/haptics/twoport.hpp"
#include "haptel/udp/arm_server.hpp"
#include "haptel/udp/udp_device.hpp"
#include "haptel/udp/udp_protocol.hpp"
#include "loopback.hpp"

using namespace haptel;
using namespace haptel::haptics;
using haptel::test::ScriptedDevice;

namespace {

using test::BoundLoopback;

constexpr int64_t kMs = 1'000'000;
constexpr Side kArm = Side::kRight;

std::size_t Idx(udp::DecodeStatus s) { return static_cast<std::size_t>(s); }

/// A UDP socket bound to 127.0.0.1 on an ephemeral port.
/// A socket connected to 127.0.0.1:port (the test's own client).
udp::UniqueFd ConnectedLoopback(int port) {
  int unused = 0;
  udp::UniqueFd fd = BoundLoopback(unused);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = htons(static_cast<uint16_t>(port));
  REQUIRE(::connect(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  return fd;
}

/// Time that moves only when told; a wait first runs `serve` (the in-process
/// server), then finds the reply there or runs out at once.
class StepClock final : public udp::Clock {
 public:
  int64_t now = 0;
  udp::ArmServer* server = nullptr;
  std::function<void()> serve;
  int64_t NowNs() override { return now; }
  WaitResult WaitReadable(int fd, int64_t deadline_ns) override {
    if (server != nullptr) server->Poll(0);
    if (serve) serve();
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 0) > 0) return WaitResult::kReadable;
    now = std::max(now, deadline_ns);
    return WaitResult::kNotYet;
  }
};

/// The right arm of a ScriptedDevice (identity units: raw = metres, command = newtons)
/// served by an ArmServer on loopback, and the test's raw client socket.
struct ServedArm {
  explicit ServedArm(bool passivity, double max_damping = 20.0) {
    udp::ArmServerOptions o;
    o.lost_after_s = 10.0;
    o.passivity = passivity;
    o.limits.max_damping = max_damping;
    o.limits.min_speed = 0.002;
    server_fd = BoundLoopback(port);
    server =
        std::make_unique<udp::ArmServer>(device, kArm, server_fd.get(), o, udp::ArmUnits{}, clock);
    client = ConnectedLoopback(port);
  }
  /// Sends `m` from the test's client and lets the server handle it at `t_ns`.
  void Send(const udp::Message& m, int64_t t_ns) {
    udp::Buffer b{};
    const std::size_t n = udp::Encode(m, b);
    REQUIRE(n > 0);
    SendBytes(std::vector<uint8_t>(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(n)), t_ns);
  }
  void SendBytes(const std::vector<uint8_t>& d, int64_t t_ns) {
    clock.now = t_ns;
    REQUIRE(::send(client.get(), d.data(), d.size(), 0) == static_cast<ssize_t>(d.size()));
    server->Poll(0);
  }
  /// The server's answer, if any, decoded.
  bool Receive(udp::Message& out) {
    std::array<uint8_t, udp::kMaxMessageSize + 1> rx{};
    const ssize_t n = ::recv(client.get(), rx.data(), rx.size(), MSG_DONTWAIT);
    if (n <= 0) return false;
    return udp::Decode(std::span<const uint8_t>(rx.data(), static_cast<std::size_t>(n)), out) ==
           udp::DecodeStatus::kOk;
  }
  ScriptedDevice device{false, true};
  StepClock clock;
  int port = 0;
  udp::UniqueFd server_fd;
  std::unique_ptr<udp::ArmServer> server;
  udp::UniqueFd client;
};

udp::EnergyReport Report(double energy_in_x, uint32_t epoch = 0) {
  udp::EnergyReport e;
  e.active = true;
  e.epoch = epoch;
  e.energy_in = {energy_in_x, 0.0, 0.0};
  return e;
}

udp::Message Request(uint32_t seq, double force_x, const udp::EnergyReport& e) {
  return udp::Message{seq, kArm, udp::WristRequest{{force_x, 0.0, 0.0}, {}, e}};
}

udp::Message Force(uint32_t seq, double force_x, const udp::EnergyReport& e) {
  return udp::Message{seq, kArm, udp::WristForce{{force_x, 0.0, 0.0}, e}};
}

}  // namespace

TEST_CASE(
    "protocol v2: the energy report round-trips; v1 leaves it out; another version is bad_version",
    "[udp][protocol][passivity]") {
  udp::EnergyReport e;
  e.active = true;
  e.epoch = 7;
  e.energy_in = {0.001, 0.002, 0.003};
  e.charged = {0.0, 0.0005, 0.0};
  e.dissipated_j = 0.25;
  e.acted_ticks = 12;
  e.max_alpha = 19.5;
  for (const udp::Message& m :
       {udp::Message{3, kArm, udp::WristRequest{{1, 2, 3}, {0, 1, 2, 3, 4}, e}},
        udp::Message{4, kArm, udp::WristReply{99, {0.1, 0.2, 0.3}, {1, 0, 0, 0}, e}},
        udp::Message{5, kArm, udp::WristForce{{-1, 0, 1}, e}}}) {
    udp::Buffer b{};
    const std::size_t n = udp::Encode(m, b);
    REQUIRE(n == udp::kHeaderSize + udp::PayloadSize(m.type(), 2));
    CHECK(b[4] == 2);  // version, little-endian
    udp::Message out;
    REQUIRE(udp::Decode(std::span<const uint8_t>(b.data(), n), out) == udp::DecodeStatus::kOk);
    CHECK(out.version == 2);
    const udp::EnergyReport* got = nullptr;
    if (const auto* p = std::get_if<udp::WristRequest>(&out.payload)) got = &p->energy;
    if (const auto* p = std::get_if<udp::WristReply>(&out.payload)) got = &p->energy;
    if (const auto* p = std::get_if<udp::WristForce>(&out.payload)) got = &p->energy;
    REQUIRE(got != nullptr);
    CHECK(got->active);
    CHECK(got->epoch == 7);
    CHECK(got->energy_in == e.energy_in);
    CHECK(got->charged == e.charged);
    CHECK(got->dissipated_j == 0.25);
    CHECK(got->acted_ticks == 12);
    CHECK(got->max_alpha == 19.5);

    // Version 1: the same message without the report, 80 bytes shorter.
    udp::Message v1 = m;
    v1.version = 1;
    const std::size_t n1 = udp::Encode(v1, b);
    CHECK(n1 == n - udp::kEnergyReportSize);
    CHECK(b[4] == 1);
    REQUIRE(udp::Decode(std::span<const uint8_t>(b.data(), n1), out) == udp::DecodeStatus::kOk);
    CHECK(out.version == 1);
  }
  // A version this code does not speak: not encoded, and rejected by its version field.
  udp::Message v3{1, kArm, udp::GloveRequest{}, 3};
  udp::Buffer b{};
  CHECK(udp::Encode(v3, b) == 0);
  udp::Message ok{1, kArm, udp::GloveRequest{}};
  const std::size_t n = udp::Encode(ok, b);
  b[4] = 3;
  udp::Message out;
  CHECK(udp::Decode(std::span<const uint8_t>(b.data(), n), out) == udp::DecodeStatus::kBadVersion);
}

TEST_CASE("protocol v2: reports are monotone counters, so a lost or late one is superseded",
          "[udp][protocol][passivity]") {
  udp::EnergyReport r1 = Report(0.001), r2 = Report(0.002), r3 = Report(0.003);
  r2.acted_ticks = 2;
  r3.acted_ticks = 3;
  r3.max_alpha = 4.0;
  // In order, with r2 lost, and with r1 arriving after r3: the same.
  const udp::EnergyReport in_order = udp::Merge(udp::Merge(udp::Merge({}, r1), r2), r3);
  const udp::EnergyReport r2_lost = udp::Merge(udp::Merge({}, r1), r3);
  const udp::EnergyReport r1_late = udp::Merge(udp::Merge(udp::Merge({}, r2), r3), r1);
  for (const udp::EnergyReport& m : {r2_lost, r1_late}) {
    CHECK(m.energy_in == in_order.energy_in);
    CHECK(m.acted_ticks == 3);
    CHECK(m.max_alpha == 4.0);
  }
  CHECK(in_order.energy_in[0] == 0.003);
  // A new epoch (the client's end restarted) replaces the counts whole.
  const udp::EnergyReport restarted = udp::Merge(in_order, Report(0.0005, 1));
  CHECK(restarted.epoch == 1);
  CHECK(restarted.energy_in[0] == 0.0005);
  CHECK(restarted.acted_ticks == 0);
}

TEST_CASE("arm server: the arm's end damps the arm by the channel's excess, hand-computed",
          "[udp][server][passivity]") {
  ServedArm s(true);
  udp::Message reply;
  // t = 1 ms: the client commands -2 N (a wall pushing the hand out) and reports
  // no energy in yet; the arm is at 0. Nothing has crossed: no damping.
  s.device.position[1] = {0.0, 0.0, 0.0};
  s.Send(Request(1, -2.0, Report(0.0)), 1 * kMs);
  REQUIRE(s.Receive(reply));
  CHECK(s.device.wrist_command[1][0] == Approx(-2.0));
  // t = 2 ms: the arm was pushed out 1 mm under the -2 N it held: 2 mJ left
  // the channel at the arm, while the loop's end reports only 1.5 mJ in.
  // W = 1.5 - 2 = -0.5 mJ. v (5 ms filter) = 1/6 * (-1 m/s) = -0.1667 m/s;
  // alpha = 0.0005 / (0.001 * 0.1667^2) = 18 N*s/m (under the 20 cap);
  // damping -alpha*v = +3 N on top of -2 N: the arm holds +1 N.
  s.device.position[1] = {-0.001, 0.0, 0.0};
  s.Send(Request(2, -2.0, Report(0.0015)), 2 * kMs);
  REQUIRE(s.Receive(reply));
  CHECK(s.device.wrist_command[1][0] == Approx(1.0).margin(1e-9));
  CHECK(s.server->counters().passivity_ticks == 1);
  CHECK(s.server->counters().passivity_max_alpha == Approx(18.0));
  CHECK(s.server->arm_end().energy_out()[0] == Approx(0.002));
  // The reply reports the arm's end: no energy in at the arm, one tick acted.
  const auto* wrist = std::get_if<udp::WristReply>(&reply.payload);
  REQUIRE(wrist != nullptr);
  CHECK(reply.version == 2);
  CHECK(wrist->energy.active);
  CHECK(wrist->energy.acted_ticks == 1);
  CHECK(wrist->energy.max_alpha == Approx(18.0));
  // t = 3 ms: another 1 mm out. The channel's -2 N delivered 2 mJ more
  // (E_out 4 mJ), the damping's +3 N took 3 mJ out of the arm (D = 3 mJ):
  // W = 1.5 - 4 + 3 = +0.5 mJ. A port that is passive is left alone.
  s.device.position[1] = {-0.002, 0.0, 0.0};
  s.Send(Request(3, -2.0, Report(0.0015)), 3 * kMs);
  REQUIRE(s.Receive(reply));
  CHECK(s.server->arm_end().dissipated()[0] == Approx(0.003));
  CHECK(s.device.wrist_command[1][0] == Approx(-2.0));
  CHECK(s.server->counters().passivity_ticks == 1);
  CHECK(s.server->counters().passivity_dissipated_j == Approx(0.003));
}

TEST_CASE("arm server: with its passivity off, or a client that does not report, it does not damp",
          "[udp][server][passivity]") {
  for (const bool server_on : {false, true}) {
    ServedArm s(server_on);
    udp::EnergyReport silent = Report(0.0);
    silent.active = server_on ? false : true;  // on: the client does not observe its end
    s.device.position[1] = {0.0, 0.0, 0.0};
    s.Send(Request(1, -2.0, silent), 1 * kMs);
    s.device.position[1] = {-0.001, 0.0, 0.0};
    s.Send(Request(2, -2.0, silent), 2 * kMs);
    CHECK(s.device.wrist_command[1][0] == Approx(-2.0));
    CHECK(s.server->counters().passivity_ticks == 0);
  }
}

TEST_CASE("arm server: a lost or late energy report changes nothing once a newer one arrives",
          "[udp][server][passivity]") {
  // Two servers run the same ticks; the second loses the one-way WRIST_FORCE
  // of tick 1 (its report of 1 mJ) and gets it late, after tick 2's request
  // (which carries a newer report): it is stale, counted and dropped.
  ServedArm a(true), b(true);
  for (ServedArm* s : {&a, &b}) {
    s->device.position[1] = {0.0, 0.0, 0.0};
    s->Send(Request(1, -2.0, Report(0.0)), 1 * kMs);
  }
  a.Send(Force(2, -2.0, Report(0.001)), 1 * kMs);
  for (ServedArm* s : {&a, &b}) {
    s->device.position[1] = {-0.001, 0.0, 0.0};
    s->Send(Request(3, -2.0, Report(0.0015)), 2 * kMs);
  }
  b.Send(Force(2, -2.0, Report(0.001)), 2 * kMs);
  CHECK(b.server->counters().stale_commands == 1);
  for (ServedArm* s : {&a, &b}) {
    s->device.position[1] = {-0.002, 0.0, 0.0};
    s->Send(Request(4, -2.0, Report(0.0015)), 3 * kMs);
  }
  CHECK(a.device.wrist_command[1][0] == Approx(b.device.wrist_command[1][0]));
  CHECK(a.server->counters().passivity_ticks == b.server->counters().passivity_ticks);
  CHECK(a.server->counters().passivity_dissipated_j ==
        Approx(b.server->counters().passivity_dissipated_j));
  CHECK(a.server->counters().passivity_ticks == 1);  // it did have to act, at tick 2
}

TEST_CASE("arm server: a v1 client is served in v1; a malformed report is counted and dropped",
          "[udp][server][passivity]") {
  ServedArm s(true);
  udp::Message v1 = Request(1, -1.0, Report(0.0));
  v1.version = 1;
  s.Send(v1, 1 * kMs);
  udp::Message reply;
  REQUIRE(s.Receive(reply));
  CHECK(reply.version == 1);
  CHECK(std::holds_alternative<udp::WristReply>(reply.payload));
  CHECK(s.server->counters().requests_by_version[1] == 1);
  CHECK(s.device.wrist_command[1][0] == Approx(-1.0));

  // Malformed v2 reports: negative energy, a reserved flag bit, NaN, a
  // version nobody speaks. None is answered or applied; each is counted.
  udp::Buffer b{};
  const std::size_t n = udp::Encode(Request(2, -3.0, Report(0.001)), b);
  REQUIRE(n > 0);
  const std::vector<uint8_t> good(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(n));
  const std::size_t report = udp::kHeaderSize + udp::kWristRequestSize;  // the report's offset
  const auto reseal = [](std::vector<uint8_t>& d) {
    for (int i = 20; i < 24; ++i) d[i] = 0;
    const uint32_t crc = udp::Crc32(d);
    for (int i = 0; i < 4; ++i) d[20 + i] = static_cast<uint8_t>(crc >> (8 * i));
  };
  const auto put_f64 = [](std::vector<uint8_t>& d, std::size_t at, double v) {
    uint64_t bits = 0;
    std::memcpy(&bits, &v, 8);
    for (int i = 0; i < 8; ++i) d[at + i] = static_cast<uint8_t>(bits >> (8 * i));
  };
  std::vector<uint8_t> negative = good;
  put_f64(negative, report + 8, -0.001);  // energy_in x
  reseal(negative);
  std::vector<uint8_t> flag = good;
  flag[report] |= 0x02;
  reseal(flag);
  std::vector<uint8_t> nan = good;
  put_f64(nan, report + 8 + 24, std::numeric_limits<double>::quiet_NaN());  // charged x
  reseal(nan);
  std::vector<uint8_t> v9 = good;
  v9[4] = 9;
  reseal(v9);
  for (const auto* d : {&negative, &flag, &nan, &v9}) s.SendBytes(*d, 2 * kMs);
  CHECK(!s.Receive(reply));
  CHECK(s.device.wrist_command[1][0] == Approx(-1.0));
  const udp::ServerCounters& c = s.server->counters();
  CHECK(c.malformed[Idx(udp::DecodeStatus::kBadValue)] == 2);
  CHECK(c.malformed[Idx(udp::DecodeStatus::kNonFinite)] == 1);
  CHECK(c.malformed[Idx(udp::DecodeStatus::kBadVersion)] == 1);
  // The good one still works after them.
  s.SendBytes(good, 2 * kMs);
  REQUIRE(s.Receive(reply));
  CHECK(reply.version == 2);
  CHECK(s.device.wrist_command[1][0] == Approx(-3.0));
}

TEST_CASE("udp device: finds a v1 server by falling back, and speaks v2 to a v2 server",
          "[udp][device][passivity]") {
  DeviceConfig config;
  config.driver = "udp";
  config.sides = {false, true};
  config.udp.retries = 0;
  config.udp.lost_after_s = 10.0;

  SECTION("a v1 server drops v2 unread; the device tries v1 and stays there") {
    int port = 0;
    udp::UniqueFd server = BoundLoopback(port);
    config.udp.arms[1] = {"127.0.0.1", port};
    StepClock clock;
    int dropped_v2 = 0;
    clock.serve = [&] {  // a version-1 server: another version is bad_version, unanswered
      std::array<uint8_t, udp::kMaxMessageSize + 1> rx{};
      sockaddr_storage from{};
      socklen_t len = sizeof from;
      for (;;) {
        const ssize_t n = ::recvfrom(server.get(), rx.data(), rx.size(), MSG_DONTWAIT,
                                     reinterpret_cast<sockaddr*>(&from), &len);
        if (n <= 0) return;
        udp::Message m;
        if (udp::Decode(std::span<const uint8_t>(rx.data(), static_cast<std::size_t>(n)), m) !=
                udp::DecodeStatus::kOk ||
            m.version != 1) {
          ++dropped_v2;
          continue;
        }
        if (m.type() != udp::MessageType::kWristRequest) continue;
        udp::Buffer b{};
        const std::size_t size = udp::Encode(
            udp::Message{m.sequence, kArm, udp::WristReply{1, {0.5, 0, 0}, {1, 0, 0, 0}}, 1}, b);
        ::sendto(server.get(), b.data(), size, 0, reinterpret_cast<sockaddr*>(&from), len);
      }
    };
    UdpDevice device(config, clock);
    WristRaw raw;
    CHECK(device.ReadWrist(kArm, 0, raw) == DeviceStatus::kNoData);  // v2: dropped
    CHECK(device.ProtocolVersion(kArm) == 1);
    CHECK(device.ReadWrist(kArm, 0, raw) == DeviceStatus::kOk);
    CHECK(raw.position[0] == 0.5);
    CHECK(device.ProtocolVersion(kArm) == 1);
    device.SetLinkEnergy(kArm, LinkEnergy{});
    CHECK(device.ReadWrist(kArm, 0, raw) == DeviceStatus::kOk);  // still v1 (no fallback back)
    CHECK(device.ProtocolVersion(kArm) == 1);
    LinkEnergy remote;
    CHECK_FALSE(device.LinkPassivity(kArm, remote));  // v1 carries no energy
    CHECK(dropped_v2 == 1);
  }

  SECTION("a v2 server with its passivity on: energy both ways") {
    ScriptedDevice arm(false, true);
    int port = 0;
    udp::UniqueFd fd = BoundLoopback(port);
    config.udp.arms[1] = {"127.0.0.1", port};
    StepClock clock;
    udp::ArmServerOptions o;
    o.passivity = true;
    udp::ArmServer server(arm, kArm, fd.get(), o, udp::ArmUnits{}, clock);
    clock.server = &server;
    UdpDevice device(config, clock);
    WristRaw raw;
    LinkEnergy remote;
    CHECK(device.ReadWrist(kArm, 0, raw) == DeviceStatus::kOk);
    CHECK(device.ProtocolVersion(kArm) == 2);
    CHECK_FALSE(
        device.LinkPassivity(kArm, remote));  // the client has not reported: the server waits
    device.SetLinkEnergy(kArm, LinkEnergy{{0.001, 0, 0}, {}, 0.0, 0, 0.0});
    CHECK(device.WriteWristForce(kArm, {-1.0, 0, 0}) == DeviceStatus::kOk);
    server.Poll(0);
    clock.now = 1 * kMs;
    CHECK(device.ReadWrist(kArm, 1 * kMs, raw) == DeviceStatus::kOk);
    CHECK(device.LinkPassivity(kArm, remote));
    CHECK(device.Counters(kArm).malformed_total() == 0);
  }
}

TEST_CASE(
    "a servo tick on the UDP device's v2 path with the two-port allocates nothing, client and "
    "server",
    "[udp][passivity][servo]") {
  DeviceConfig config;
  config.safety.soft_start_s = 0.0;
  config.safety.max_force_rate = 1e6;
  config.servo.realtime_priority = 0;
  config.servo.lock_memory = false;
  config.servo.passivity = true;
  config.driver = "udp";
  config.sides = {false, true};
  config.has_glove = false;
  config.has_grasp = false;
  config.udp.lost_after_s = 10.0;
  SECTION("the loop's end charging its deficit to the arm's (the default)") {
    config.servo.passivity_link_admittance = false;
  }
  SECTION("the loop's end's admittance") { config.servo.passivity_link_admittance = true; }
  ScriptedDevice arm(false, true);
  int port = 0;
  udp::UniqueFd fd = BoundLoopback(port);
  config.udp.arms[1] = {"127.0.0.1", port};
  StepClock clock;
  udp::ArmServerOptions o;
  o.passivity = true;
  o.delay_s = 0.003;
  o.lost_after_s = 10.0;
  udp::ArmServer server(arm, kArm, fd.get(), o, udp::ArmUnits{}, clock);
  clock.server = &server;
  UdpDevice device(config, clock);
  DeviceCalibration identity;
  for (auto& a : identity.arms) a.tracker_scale = {1, 1, 1};
  Hal hal(identity);
  ServoLoop loop(device, hal, config, identity);
  ForceSetpoint wall;
  wall.coupling_enabled = true;
  wall.coupling_stiffness = 3000;
  const auto tick = [&](int i) {
    clock.now = i * kMs;
    // The arm oscillates through the wall: the delayed channel leaks and both ends act.
    arm.position[1] = {0.01 * std::sin(i * 0.05), 0, 0};
    wall.coupling_target = {std::min(0.0, arm.position[1][0]), 0, 0};
    hal.SetSetpoint(kArm, wall, i * kMs);
    loop.Tick(kArm, i * kMs);
    server.Poll(0);  // the one-way force, as a real-time server would at once
  };
  for (int i = 1; i <= 50; ++i) tick(i);  // warm up
  const uint64_t before = test::ThreadAllocations();
  for (int i = 51; i < 2000; ++i) tick(i);
  CHECK(test::ThreadAllocations() == before);
  const ServoCounters c = loop.Counters(kArm);
  CHECK(device.ProtocolVersion(kArm) == 2);
  CHECK(c.passivity_link_ticks > 1900);
  CHECK(c.passivity_device_ticks > 0);  // the server's end acted, and said so
  // The reports ride the delayed readings: the loop knows the server's count of 3 ms ago.
  CHECK(c.passivity_device_ticks <= server.counters().passivity_ticks);
  CHECK(c.passivity_device_ticks + 10 >= server.counters().passivity_ticks);
  CHECK(device.Counters(kArm).malformed_total() == 0);
}
