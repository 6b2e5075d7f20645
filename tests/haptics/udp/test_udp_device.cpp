// UdpDevice against an in-process fake arm server (every misbehaviour on
// demand) and against real haptel-device-server processes, one per arm.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "../../e2e/child.hpp"
#include "alloc_counter.hpp"
#include "haptel/config/device.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/udp/udp_device.hpp"
#include "haptel/udp/udp_protocol.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {

std::size_t Idx(udp::DecodeStatus s) { return static_cast<std::size_t>(s); }
std::size_t Idx(udp::ErrorCode c) { return static_cast<std::size_t>(c); }

/// A UDP socket bound to 127.0.0.1 on an ephemeral port.
udp::UniqueFd BoundLoopback(int& port) {
  udp::UniqueFd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
  REQUIRE(fd.get() >= 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  REQUIRE(::bind(fd.get(), reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  socklen_t len = sizeof addr;
  REQUIRE(::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&addr), &len) == 0);
  port = ntohs(addr.sin_port);
  return fd;
}

/// An in-process stand-in for one arm's server, misbehaving on demand.
class FakeArm {
 public:
  enum class Mode {
    kNormal,        ///< answer every request correctly
    kSilent,        ///< answer nothing
    kStaleFirst,    ///< before the answer: a reply to the previous and one to the next sequence
    kGarbageFirst,  ///< before the answer: short, bad-magic, bad-version and bad-checksum datagrams
    kDuplicate,     ///< the answer, twice
    kWrongTypeFirst,    ///< before the answer: a reply of the other type with the right sequence
    kErrorBusy,         ///< ERROR busy
    kErrorDeviceLost,   ///< ERROR device_lost
    kDropFirstAttempt,  ///< ignore the first copy of each request; answer its retry
  };
  struct Seen {
    int wrist_requests = 0;
    int glove_requests = 0;
    int wrist_forces = 0;
    int finger_forces = 0;
    udp::WristRequest last_request;
    Vec3d last_wrist_force{};
    std::array<double, kFingers> last_finger_force{};
    uint32_t last_sequence = 0;
  };

  explicit FakeArm(Side side) : side_(side), socket_(BoundLoopback(port_)) {
    thread_ = std::thread([this] { Run(); });
  }
  ~FakeArm() {
    stop_ = true;
    thread_.join();
  }
  int port() const { return port_; }
  void set_mode(Mode mode) { mode_ = mode; }
  Seen seen() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_;
  }

 private:
  void Run() {
    std::array<uint8_t, 2048> rx{};
    while (!stop_) {
      pollfd p{socket_.get(), POLLIN, 0};
      if (::poll(&p, 1, 10) <= 0) continue;
      sockaddr_storage from{};
      socklen_t from_len = sizeof from;
      const ssize_t n = ::recvfrom(socket_.get(), rx.data(), rx.size(), 0,
                                   reinterpret_cast<sockaddr*>(&from), &from_len);
      if (n < 0) continue;
      udp::Message m;
      if (udp::Decode(std::span<const uint8_t>(rx.data(), static_cast<std::size_t>(n)), m) !=
          udp::DecodeStatus::kOk) {
        continue;
      }
      Handle(m, from, from_len);
    }
  }

  void Send(const udp::Message& m, const sockaddr_storage& to, socklen_t len) {
    udp::Buffer b{};
    const std::size_t n = udp::Encode(m, b);
    SendBytes(std::span<const uint8_t>(b.data(), n), to, len);
  }
  void SendBytes(std::span<const uint8_t> bytes, const sockaddr_storage& to, socklen_t len) {
    ::sendto(socket_.get(), bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&to),
             len);
  }

  void Handle(const udp::Message& m, const sockaddr_storage& from, socklen_t len) {
    udp::Payload answer;
    udp::Payload wrong_type;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      seen_.last_sequence = m.sequence;
      if (const auto* r = std::get_if<udp::WristRequest>(&m.payload)) {
        ++seen_.wrist_requests;
        seen_.last_request = *r;
        // A pose that changes every request and names the side: x counts, y is the side.
        answer =
            udp::WristReply{MonotonicNs(),
                            {static_cast<double>(seen_.wrist_requests), 10.0 * Index(side_), -1.0},
                            {1, 0, 0, 0}};
        wrong_type = udp::GloveReply{};
      } else if (std::holds_alternative<udp::GloveRequest>(m.payload)) {
        ++seen_.glove_requests;
        udp::GloveReply g{MonotonicNs(), {}, {}};
        for (int j = 0; j < kGloveJoints; ++j) g.sensors[j] = j + 100.0 * Index(side_);
        for (int f = 0; f < kFingers; ++f) g.grasp[f] = seen_.last_finger_force[f];
        answer = g;
        wrong_type = udp::WristReply{};
      } else if (const auto* w = std::get_if<udp::WristForce>(&m.payload)) {
        ++seen_.wrist_forces;
        seen_.last_wrist_force = w->command;
        return;
      } else if (const auto* f = std::get_if<udp::FingerForce>(&m.payload)) {
        ++seen_.finger_forces;
        seen_.last_finger_force = f->command;
        return;
      } else {
        return;
      }
    }
    const udp::Message reply{m.sequence, m.side, answer};
    switch (mode_.load()) {
      case Mode::kNormal:
        Send(reply, from, len);
        break;
      case Mode::kSilent:
        break;
      case Mode::kStaleFirst:
        Send(udp::Message{m.sequence - 1, m.side, answer}, from, len);
        Send(udp::Message{m.sequence + 1, m.side, answer}, from, len);
        Send(reply, from, len);
        break;
      case Mode::kGarbageFirst: {
        udp::Buffer b{};
        const std::size_t n = udp::Encode(reply, b);
        const std::array<uint8_t, 7> junk{'g', 'a', 'r', 'b', 'a', 'g', 'e'};
        SendBytes(junk, from, len);
        udp::Buffer magic = b;
        magic[0] = 'X';
        SendBytes(std::span<const uint8_t>(magic.data(), n), from, len);
        udp::Buffer version = b;
        version[4] = 9;
        SendBytes(std::span<const uint8_t>(version.data(), n), from, len);
        udp::Buffer corrupt = b;
        corrupt[n - 1] ^= 0x40;
        SendBytes(std::span<const uint8_t>(corrupt.data(), n), from, len);
        Send(reply, from, len);
        break;
      }
      case Mode::kDuplicate:
        Send(reply, from, len);
        Send(reply, from, len);
        break;
      case Mode::kWrongTypeFirst:
        Send(udp::Message{m.sequence, m.side, wrong_type}, from, len);
        Send(reply, from, len);
        break;
      case Mode::kErrorBusy:
        Send(udp::Message{m.sequence, m.side, udp::ErrorReply{udp::ErrorCode::kBusy}}, from, len);
        break;
      case Mode::kErrorDeviceLost:
        Send(udp::Message{m.sequence, m.side, udp::ErrorReply{udp::ErrorCode::kDeviceLost}}, from,
             len);
        break;
      case Mode::kDropFirstAttempt:
        if (m.sequence == dropped_) {
          Send(reply, from, len);
        } else {
          dropped_ = m.sequence;
        }
        break;
    }
  }

  Side side_;
  int port_ = 0;
  udp::UniqueFd socket_;
  std::atomic<bool> stop_{false};
  std::atomic<Mode> mode_{Mode::kNormal};
  uint32_t dropped_ = 0;
  mutable std::mutex mutex_;
  Seen seen_;
  std::thread thread_;
};

/// A udp device configuration for loopback servers (port 0: side absent).
/// Generous timeouts: a loaded test machine must not turn replies into timeouts.
DeviceConfig LoopbackConfig(int left_port, int right_port, double timeout_s = 0.25, int retries = 1,
                            double lost_after_s = 1.0) {
  DeviceConfig c;
  c.name = "udp-test";
  c.driver = "udp";
  c.sides = {left_port != 0, right_port != 0};
  c.udp.arms[0] = {"127.0.0.1", left_port};
  c.udp.arms[1] = {"127.0.0.1", right_port};
  c.udp.timeout_s = timeout_s;
  c.udp.retries = retries;
  c.udp.lost_after_s = lost_after_s;
  c.safety.wrist_force_limit = 5.0;
  c.safety.finger_force_limit = 4.0;
  return c;
}

}  // namespace

TEST_CASE("udp device: description comes from the config", "[udp][device]") {
  FakeArm right(Side::kRight);
  DeviceConfig config = LoopbackConfig(0, right.port());
  config.has_glove = false;
  UdpDevice device(config);
  CHECK(device.description().name == "udp-test");
  CHECK_FALSE(device.HasSide(Side::kLeft));
  CHECK(device.HasSide(Side::kRight));
  CHECK(device.description().wrist_force_limit == 5.0);
  CHECK(device.description().finger_force_limit == 4.0);
  CHECK_FALSE(device.description().has_glove);
  WristRaw raw;
  CHECK(device.ReadWrist(Side::kLeft, MonotonicNs(), raw) ==
        DeviceStatus::kLost);  // not configured
}

TEST_CASE("udp device: set-up errors name the key and host:port", "[udp][device]") {
  DeviceConfig unresolvable = LoopbackConfig(4000, 0);
  unresolvable.file = "config/devices/arms.yaml";
  unresolvable.udp.arms[0].host = "no-such-host.invalid";
  try {
    UdpDevice device(unresolvable);
    FAIL("expected an exception");
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    CHECK(what.find("config/devices/arms.yaml") != std::string::npos);
    CHECK(what.find("udp.left") != std::string::npos);
    CHECK(what.find("no-such-host.invalid:4000") != std::string::npos);
  }
  DeviceConfig no_port = LoopbackConfig(4000, 0);
  no_port.sides = {true, true};  // the right arm has no port
  CHECK_THROWS_WITH(UdpDevice(no_port),
                    Catch::Contains("udp.right") && Catch::Contains("127.0.0.1:0"));
}

TEST_CASE("udp device: reads and commands go over the wire", "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0));
  WristRaw raw;
  REQUIRE(device.ReadWrist(Side::kLeft, 1234, raw) == DeviceStatus::kOk);
  CHECK(raw.t_ns == 1234);  // stamped with the servo's time, not the server's
  CHECK(raw.position == Vec3d{1.0, 0.0, -1.0});
  CHECK(raw.orientation == std::array<double, 4>{1, 0, 0, 0});
  REQUIRE(device.ReadWrist(Side::kLeft, 1235, raw) == DeviceStatus::kOk);
  CHECK(raw.position[0] == 2.0);  // fresh every call

  // Commands go out one-way at once, and ride on the next request.
  CHECK(device.WriteWristForce(Side::kLeft, {0.5, -1.0, 2.0}) == DeviceStatus::kOk);
  CHECK(device.WriteFingerForces(Side::kLeft, {1, 2, 3, 4, 5}) == DeviceStatus::kOk);
  REQUIRE(test::WaitFor([&] { return arm.seen().finger_forces == 1; }, 5.0));
  CHECK(arm.seen().wrist_forces == 1);
  CHECK(arm.seen().last_wrist_force == Vec3d{0.5, -1.0, 2.0});
  REQUIRE(device.ReadWrist(Side::kLeft, 1236, raw) == DeviceStatus::kOk);
  CHECK(arm.seen().last_request.wrist_force == Vec3d{0.5, -1.0, 2.0});
  CHECK(arm.seen().last_request.finger_forces == std::array<double, kFingers>{1, 2, 3, 4, 5});

  GloveRaw glove;
  REQUIRE(device.ReadGlove(Side::kLeft, 77, glove) == DeviceStatus::kOk);
  CHECK(glove.t_ns == 77);
  CHECK(glove.sensors[21] == 21.0);
  CHECK(glove.grasp == std::array<double, kFingers>{1, 2, 3, 4, 5});

  const UdpCounters c = device.Counters(Side::kLeft);
  CHECK(c.requests == 4);
  CHECK(c.replies == 4);
  CHECK(c.forces_sent == 2);
  CHECK(c.timeouts == 0);
  CHECK(c.stale == 0);
  CHECK(c.malformed_total() == 0);
  CHECK(device.Counters().requests == 4);  // both sides summed; right has none
}

TEST_CASE("udp device: invalid commands are sent as zero and counted", "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  device.WriteWristForce(Side::kLeft, {1.0, nan, 1.0});
  device.WriteFingerForces(Side::kLeft,
                           {1.0, -2.0, std::numeric_limits<double>::infinity(), 1.0, 1.0});
  REQUIRE(test::WaitFor([&] { return arm.seen().finger_forces == 1; }, 5.0));
  CHECK(arm.seen().last_wrist_force == Vec3d{0, 0, 0});
  CHECK(arm.seen().last_finger_force == std::array<double, kFingers>{1, 0, 0, 1, 1});
  CHECK(device.Counters(Side::kLeft).invalid_commands == 2);
}

TEST_CASE(
    "udp device: stale, out-of-order, malformed and mistyped replies are rejected and counted",
    "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0));
  WristRaw raw;

  SECTION("replies to other sequence numbers") {
    arm.set_mode(FakeArm::Mode::kStaleFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    CHECK(raw.position[0] == 1.0);
    const UdpCounters c = device.Counters(Side::kLeft);
    CHECK(c.stale == 2);  // one older, one newer than the outstanding request
    CHECK(c.replies == 1);
  }
  SECTION("duplicates") {
    arm.set_mode(FakeArm::Mode::kDuplicate);
    for (int i = 0; i < 5; ++i) REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    // Each duplicate is read (and rejected) by the next call at the latest.
    CHECK(device.Counters(Side::kLeft).stale == 4);
    CHECK(device.Counters(Side::kLeft).replies == 5);
  }
  SECTION("malformed datagrams") {
    arm.set_mode(FakeArm::Mode::kGarbageFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    GloveRaw glove;
    REQUIRE(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kOk);
    const UdpCounters c = device.Counters(Side::kLeft);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kShort)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadMagic)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadVersion)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadChecksum)] == 2);
    CHECK(c.malformed_total() == 8);
    CHECK(c.replies == 2);
  }
  SECTION("the right sequence but the wrong type") {
    arm.set_mode(FakeArm::Mode::kWrongTypeFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    GloveRaw glove;
    REQUIRE(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kOk);
    CHECK(device.Counters(Side::kLeft).unexpected == 2);
  }
}

TEST_CASE("udp device: a reply from the other arm's server is not trusted", "[udp][device]") {
  // A server that answers a left-arm request as the right arm (the real
  // server answers ERROR wrong_side instead; see the server test below).
  int port = 0;
  udp::UniqueFd forger = BoundLoopback(port);
  UdpDevice device(LoopbackConfig(port, 0, 0.1, 0));
  std::thread server([&] {
    std::array<uint8_t, 512> rx{};
    sockaddr_storage from{};
    socklen_t len = sizeof from;
    const ssize_t n =
        ::recvfrom(forger.get(), rx.data(), rx.size(), 0, reinterpret_cast<sockaddr*>(&from), &len);
    udp::Message m;
    if (n <= 0 || udp::Decode(std::span<const uint8_t>(rx.data(), static_cast<std::size_t>(n)),
                              m) != udp::DecodeStatus::kOk) {
      return;
    }
    udp::Buffer b{};
    const std::size_t size = udp::Encode(
        udp::Message{m.sequence, Side::kRight, udp::WristReply{0, {1, 2, 3}, {1, 0, 0, 0}}}, b);
    ::sendto(forger.get(), b.data(), size, 0, reinterpret_cast<const sockaddr*>(&from), len);
  });
  WristRaw raw;
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
  server.join();
  CHECK(device.Counters(Side::kLeft).unexpected == 1);
  CHECK(device.Counters(Side::kLeft).replies == 0);
}

TEST_CASE("udp device: timeouts and retries are counted", "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0, 0.05, 2, 30.0));
  WristRaw raw;
  SECTION("an answered retry") {
    arm.set_mode(FakeArm::Mode::kDropFirstAttempt);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    const UdpCounters c = device.Counters(Side::kLeft);
    CHECK(c.timeouts == 1);
    CHECK(c.retries == 1);
    CHECK(c.unanswered == 0);
    CHECK(arm.seen().wrist_requests == 2);  // the same request, sent twice
  }
  SECTION("silence") {
    arm.set_mode(FakeArm::Mode::kSilent);
    CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
    const UdpCounters c = device.Counters(Side::kLeft);
    CHECK(c.timeouts == 3);  // 1 + retries
    CHECK(c.retries == 2);
    CHECK(c.unanswered == 1);
    CHECK(c.replies == 0);
  }
  SECTION("ERROR busy ends the wait without a timeout") {
    arm.set_mode(FakeArm::Mode::kErrorBusy);
    CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
    const UdpCounters c = device.Counters(Side::kLeft);
    CHECK(c.errors[Idx(udp::ErrorCode::kBusy)] == 1);
    CHECK(c.timeouts == 0);
  }
}

TEST_CASE("udp device: silence turns a side lost after lost_after_s; answers bring it back",
          "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0, 0.02, 1, 0.3));
  WristRaw raw;
  REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
  arm.set_mode(FakeArm::Mode::kSilent);
  // Until lost_after_s has passed without a valid reply: no data, not lost.
  const DeviceStatus first = device.ReadWrist(Side::kLeft, 0, raw);
  CHECK(first != DeviceStatus::kOk);
  DeviceStatus status = first;
  REQUIRE(test::WaitFor(
      [&] { return (status = device.ReadWrist(Side::kLeft, 0, raw)) == DeviceStatus::kLost; },
      10.0));
  CHECK(device.Lost(Side::kLeft));
  CHECK(device.Counters(Side::kLeft).lost_transitions == 1);
  CHECK(device.WriteWristForce(Side::kLeft, {0, 0, 0}) == DeviceStatus::kLost);
  // Lost stays lost, probed with one attempt per call (no retries).
  const UdpCounters before = device.Counters(Side::kLeft);
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);
  GloveRaw glove;
  CHECK(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kLost);
  const UdpCounters after = device.Counters(Side::kLeft);
  CHECK(after.timeouts - before.timeouts == 2);
  CHECK(after.retries == before.retries);
  CHECK(after.lost_transitions == 1);

  arm.set_mode(FakeArm::Mode::kNormal);
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
  CHECK_FALSE(device.Lost(Side::kLeft));
  CHECK(device.Counters(Side::kLeft).recoveries == 1);
  CHECK(device.WriteWristForce(Side::kLeft, {0, 0, 0}) == DeviceStatus::kOk);
}

TEST_CASE("udp device: no server on the port: no data, then lost, errors counted",
          "[udp][device]") {
  int port = 0;
  {
    udp::UniqueFd closed = BoundLoopback(port);  // a port nobody listens on once this closes
  }
  UdpDevice device(LoopbackConfig(port, 0, 0.01, 0, 0.1));
  WristRaw raw;
  DeviceStatus status = DeviceStatus::kOk;
  REQUIRE(test::WaitFor(
      [&] { return (status = device.ReadWrist(Side::kLeft, 0, raw)) == DeviceStatus::kLost; },
      10.0));
  const UdpCounters c = device.Counters(Side::kLeft);
  CHECK(c.replies == 0);
  CHECK(c.unanswered == c.requests);
  CHECK(c.socket_errors > 0);  // ICMP port unreachable shows as ECONNREFUSED on a connected socket
  CHECK(c.lost_transitions == 1);
}

TEST_CASE("udp device: ERROR device_lost makes the side lost at once", "[udp][device]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0, 0.25, 1, 60.0));
  WristRaw raw;
  arm.set_mode(FakeArm::Mode::kErrorDeviceLost);
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);
  CHECK(device.Counters(Side::kLeft).errors[Idx(udp::ErrorCode::kDeviceLost)] == 1);
  CHECK(device.Counters(Side::kLeft).lost_transitions == 1);
  arm.set_mode(FakeArm::Mode::kNormal);
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
  CHECK(device.Counters(Side::kLeft).recoveries == 1);
}

TEST_CASE("udp device: the servo calls allocate nothing, on good and bad paths",
          "[udp][device][alloc]") {
  FakeArm arm(Side::kLeft);
  UdpDevice device(LoopbackConfig(arm.port(), 0, 0.02, 1, 0.05));
  WristRaw raw;
  GloveRaw glove;
  const auto cycles = [&](int n) {
    for (int i = 0; i < n; ++i) {
      device.ReadWrist(Side::kLeft, i, raw);
      device.WriteWristForce(Side::kLeft, {0.1 * i, 0, 0});
      device.WriteFingerForces(Side::kLeft, {1, 1, 1, 1, 1});
      if (i % 6 == 0) device.ReadGlove(Side::kLeft, i, glove);
    }
  };
  cycles(10);  // warm-up
  for (const auto mode :
       {FakeArm::Mode::kNormal, FakeArm::Mode::kStaleFirst, FakeArm::Mode::kGarbageFirst,
        FakeArm::Mode::kDuplicate, FakeArm::Mode::kErrorBusy, FakeArm::Mode::kSilent,
        FakeArm::Mode::kNormal}) {
    arm.set_mode(mode);
    const uint64_t before = test::ThreadAllocations();
    cycles(mode == FakeArm::Mode::kSilent ? 5 : 200);
    CHECK(test::ThreadAllocations() == before);
  }
  CHECK(device.Counters(Side::kLeft).replies > 0);
}

TEST_CASE("udp device: two sides on two threads at once", "[udp][device]") {
  FakeArm left(Side::kLeft);
  FakeArm right(Side::kRight);
  UdpDevice device(LoopbackConfig(left.port(), right.port()));
  constexpr int kCycles = 500;
  std::array<int, kSides> ok{};
  std::array<bool, kSides> side_seen_right{};
  const auto drive = [&](Side side) {
    WristRaw raw;
    for (int i = 0; i < kCycles; ++i) {
      if (device.ReadWrist(side, i, raw) == DeviceStatus::kOk) ++ok[Index(side)];
      // The fake puts 10 × side in y: each side hears only its own server.
      side_seen_right[Index(side)] = raw.position[1] == 10.0 * Index(side);
      device.WriteWristForce(side, {static_cast<double>(Index(side)), 0, 0});
    }
  };
  std::thread a(drive, Side::kLeft);
  std::thread b(drive, Side::kRight);
  a.join();
  b.join();
  CHECK(ok[0] == kCycles);
  CHECK(ok[1] == kCycles);
  CHECK(side_seen_right[0]);
  CHECK(side_seen_right[1]);
  CHECK(device.Counters(Side::kLeft).replies == kCycles);
  CHECK(device.Counters(Side::kRight).replies == kCycles);
  CHECK(right.seen().last_wrist_force == Vec3d{1, 0, 0});
  CHECK(device.Counters().stale == 0);
}

// --- Against the real haptel-device-server, one process per arm. ---

namespace {

/// A running haptel-device-server; the port it bound is parsed from its ready line.
struct Server {
  test::Child child;
  int port = 0;
  Server(const std::string& side, const std::string& device)
      : child({(test::BinDir() / "haptel-device-server").string(), "--device", device, "--side",
               side, "--port", "0"}) {
    const bool ready = test::WaitFor(
        [&] {
          child.Pump();
          return child.out().find('\n') != std::string::npos ||
                 child.Wait(0) != test::Child::kRunning;
        },
        20.0);
    REQUIRE(ready);
    const std::string line = child.out().substr(0, child.out().find('\n'));
    INFO(line << child.err());
    REQUIRE(line.find("haptel-device-server: serving " + side + " arm of 'sim' on 127.0.0.1:") ==
            0);
    port = std::stoi(line.substr(line.rfind(':') + 1));
    REQUIRE(port > 0);
  }
};

/// sim.yaml with a longer client watchdog, so a second client is surely refused.
std::string DeviceFileWithWatchdog(double lost_after_s) {
  const auto dir = test::ScratchDir("udp-device");
  std::ifstream in("config/devices/sim.yaml");
  std::stringstream text;
  text << in.rdbuf();
  text << "\nudp:\n  lost_after_s: " << lost_after_s << "\n";
  const auto file = dir / "sim-watchdog.yaml";
  std::ofstream(file) << text.str();
  return file.string();
}

}  // namespace

TEST_CASE("udp device against two haptel-device-server processes", "[udp][server]") {
  const std::string device_file = DeviceFileWithWatchdog(2.0);
  Server left("left", device_file);
  Server right("right", device_file);
  UdpDevice device(LoopbackConfig(left.port, right.port, 0.25, 2, 2.0));

  // Plausible raw values: the tracker reports about centimetres inside the
  // workspace box, an identity orientation, finite glove counts.
  WristRaw raw;
  GloveRaw glove;
  for (const Side side : {Side::kLeft, Side::kRight}) {
    REQUIRE(device.ReadWrist(side, MonotonicNs(), raw) == DeviceStatus::kOk);
    for (double v : raw.position) {
      CHECK(std::isfinite(v));
      CHECK(std::abs(v) < 40.0);
    }
    CHECK(raw.orientation == std::array<double, 4>{1, 0, 0, 0});
    REQUIRE(device.ReadGlove(side, MonotonicNs(), glove) == DeviceStatus::kOk);
    for (double v : glove.sensors) CHECK(std::isfinite(v));
  }

  // A constant +x force on the left arm pushes it along x; the right arm,
  // with no force, does not move along x. Each side on its own thread.
  std::array<Vec3d, kSides> start{};
  std::array<Vec3d, kSides> last{};
  std::atomic<bool> moved{false};
  std::array<int, kSides> ok{};
  const auto drive = [&](Side side) {
    const int s = Index(side);
    WristRaw r;
    const int64_t give_up = MonotonicNs() + SToNs(10.0);
    for (int i = 0; !moved.load() && MonotonicNs() < give_up; ++i) {
      if (device.ReadWrist(side, MonotonicNs(), r) != DeviceStatus::kOk) continue;
      if (ok[s]++ == 0) start[s] = r.position;
      last[s] = r.position;
      if (side == Side::kLeft && last[s][0] - start[s][0] > 5.0)
        moved = true;  // 5 raw units ≈ 5 cm
      device.WriteWristForce(side, side == Side::kLeft ? Vec3d{3.0, 0, 0} : Vec3d{0, 0, 0});
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  };
  std::thread a(drive, Side::kLeft);
  std::thread b(drive, Side::kRight);
  a.join();
  b.join();
  CHECK(moved.load());
  CHECK(ok[0] > 1);
  CHECK(ok[1] > 1);
  CHECK(last[0][0] - start[0][0] > 5.0);
  CHECK(std::abs(last[1][0] - start[1][0]) < 0.5);

  // Finger commands reach the grasp strings and come back as measured values.
  REQUIRE(device.WriteFingerForces(Side::kRight, {0.5, 1.0, 1.5, 2.0, 2.5}) == DeviceStatus::kOk);
  REQUIRE(device.ReadGlove(Side::kRight, MonotonicNs(), glove) == DeviceStatus::kOk);
  for (int f = 0; f < kFingers; ++f) CHECK(glove.grasp[f] == Approx(0.5 * (f + 1)).margin(1e-9));

  SECTION("a second client is refused while the first holds the arm") {
    UdpDevice intruder(LoopbackConfig(left.port, 0, 0.25, 0, 60.0));
    REQUIRE(device.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk);
    CHECK(intruder.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kNoData);
    CHECK(intruder.Counters().errors[Idx(udp::ErrorCode::kBusy)] == 1);
  }
  SECTION("an arm pointed at the other arm's server gets ERROR wrong_side") {
    UdpDevice swapped(LoopbackConfig(right.port, 0, 0.25, 0, 60.0));
    CHECK(swapped.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kNoData);
    CHECK(swapped.Counters().errors[Idx(udp::ErrorCode::kWrongSide)] == 1);
  }
  bool sent_garbage = false;
  SECTION("garbage does not hurt the server") {
    sent_garbage = true;
    udp::UniqueFd raw_socket(::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0));
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    to.sin_port = htons(static_cast<uint16_t>(left.port));
    std::mt19937 rng(7);
    std::array<uint8_t, 600> junk{};
    for (int i = 0; i < 500; ++i) {
      for (auto& b : junk) b = static_cast<uint8_t>(rng());
      if (i % 2 == 0) std::copy(udp::kMagic.begin(), udp::kMagic.end(), junk.begin());
      ::sendto(raw_socket.get(), junk.data(), rng() % junk.size(), 0,
               reinterpret_cast<sockaddr*>(&to), sizeof to);
    }
    REQUIRE(device.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk);
    CHECK(left.child.Wait(0) == test::Child::kRunning);
  }

  // SIGTERM: a clean exit with a summary.
  ::kill(left.child.pid(), SIGTERM);
  ::kill(right.child.pid(), SIGTERM);
  CHECK(left.child.Wait(10.0) == 0);
  CHECK(right.child.Wait(10.0) == 0);
  CHECK(left.child.err().find("stopped:") != std::string::npos);
  if (sent_garbage) {
    CHECK(left.child.err().find("bad_magic=") != std::string::npos);
    CHECK(left.child.err().find("short=") != std::string::npos);
  }
}

TEST_CASE("haptel-device-server: a silent client trips the watchdog and frees the arm",
          "[udp][server]") {
  Server left("left", DeviceFileWithWatchdog(0.05));
  WristRaw raw;
  {
    UdpDevice first(LoopbackConfig(left.port, 0, 0.25, 2, 2.0));
    REQUIRE(first.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk);
    first.WriteWristForce(Side::kLeft, {2.0, 0, 0});
  }
  // Once the first client has been quiet for the watchdog time, another takes over.
  UdpDevice second(LoopbackConfig(left.port, 0, 0.25, 0, 60.0));
  REQUIRE(test::WaitFor(
      [&] { return second.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk; },
      10.0));
  ::kill(left.child.pid(), SIGTERM);
  REQUIRE(left.child.Wait(10.0) == 0);
  INFO(left.child.err());
  CHECK(left.child.err().find(" 0 watchdog trips") == std::string::npos);
}

TEST_CASE("haptel-device-server: bad arguments and configuration exit 2 with one line",
          "[udp][server]") {
  const std::string bin = (test::BinDir() / "haptel-device-server").string();
  const std::vector<std::vector<std::string>> cases = {
      {bin, "--side", "middle", "--port", "0"},
      {bin, "--side", "left"},
      {bin, "--side", "left", "--port", "70000"},
      {bin, "--side", "left", "--port", "0", "--device", "no/such/device.yaml"},
      {bin, "--side", "left", "--port", "0", "--bogus", "1"},
      {bin, "--side", "left", "--port", "0", "--bind", "no-such-host.invalid"},
  };
  for (const auto& argv : cases) {
    test::Child child(argv);
    const int code = child.Wait(20.0);
    INFO(argv[2] << " " << argv.back() << ": " << child.err());
    CHECK(code == 2);
    CHECK(std::count(child.err().begin(), child.err().end(), '\n') == 1);
    CHECK(child.out().empty());
  }
}
