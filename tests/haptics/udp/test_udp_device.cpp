// UdpDevice against an in-process fake arm server (every misbehaviour on
// demand) and against real haptel-device-server processes, one per arm.
//
// Timeouts, retries and the lost timer run on a FakeClock wherever a test
// counts them: its time moves only when a wait has nothing coming, so each
// count is exact however loaded the machine is. The real clock remains where
// the test is about sockets and processes, with generous timeouts that only a
// fault reaches.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <limits>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "../../e2e/child.hpp"
#include "alloc_counter.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/udp/udp_device.hpp"
#include "haptel/udp/udp_protocol.hpp"
#include "loopback.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {

using test::BoundLoopback;

constexpr int64_t kMs = 1'000'000;
/// How long a fake waits for something that must happen (a datagram handled
/// or delivered on loopback): only a fault takes this long.
constexpr double kFaultAfter_s = 10.0;

std::size_t Idx(udp::DecodeStatus s) { return static_cast<std::size_t>(s); }
std::size_t Idx(udp::ErrorCode c) { return static_cast<std::size_t>(c); }

/// Datagrams the device has read and classified: each lands in one counter.
uint64_t Received(const UdpCounters& c) {
  uint64_t n = c.replies + c.stale + c.unexpected + c.malformed_total();
  for (const uint64_t e : c.errors) n += e;
  return n;
}

/// Datagrams the device has sent (every request attempt and one-way command).
uint64_t Sent(const UdpCounters& c) { return c.requests + c.retries + c.forces_sent; }

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
    kOtherSide,         ///< the answer, but as the other arm (a forger or a mix-up)
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

  explicit FakeArm(Side side)
      : side_(side), socket_(BoundLoopback(port_)), thread_("fake arm", [this] { Run(); }) {}
  ~FakeArm() {
    stop_ = true;
    thread_.Join();
  }
  int port() const { return port_; }
  void set_mode(Mode mode) { mode_ = mode; }
  Seen seen() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return seen_;
  }
  /// Datagrams sent to the client so far.
  uint64_t sent() const { return sent_.load(); }
  /// Waits (bounded) until `count` datagrams have been received and fully
  /// handled, answers sent; false if they never come.
  bool WaitHandled(uint64_t count) {
    std::unique_lock<std::mutex> lock(mutex_);
    return handled_cv_.wait_for(lock, std::chrono::duration<double>(kFaultAfter_s),
                                [&] { return handled_ >= count; });
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
      if (udp::Decode(std::span<const uint8_t>(rx.data(), static_cast<std::size_t>(n)), m) ==
          udp::DecodeStatus::kOk) {
        Handle(m, from, from_len);
      }
      std::lock_guard<std::mutex> lock(mutex_);
      ++handled_;
      handled_cv_.notify_all();
    }
  }

  void Send(const udp::Message& m, const sockaddr_storage& to, socklen_t len) {
    udp::Buffer b{};
    const std::size_t n = udp::Encode(m, b);
    SendBytes(std::span<const uint8_t>(b.data(), n), to, len);
  }
  void SendBytes(std::span<const uint8_t> bytes, const sockaddr_storage& to, socklen_t len) {
    if (::sendto(socket_.get(), bytes.data(), bytes.size(), 0,
                 reinterpret_cast<const sockaddr*>(&to), len) >= 0) {
      ++sent_;
    }
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
      case Mode::kOtherSide:
        Send(udp::Message{m.sequence, m.side == Side::kLeft ? Side::kRight : Side::kLeft, answer},
             from, len);
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
  std::atomic<uint64_t> sent_{0};
  mutable std::mutex mutex_;
  std::condition_variable handled_cv_;
  uint64_t handled_ = 0;
  Seen seen_;
  test::Thread thread_;  // last: starts once the members above exist
};

/// A udp::Clock whose time moves only when told, for one device side driven
/// from the test's thread. A device's wait never sleeps on it: it asks the
/// rig what is on the wire once the server has handled everything the device
/// sent. Something on its way to the device: the wait returns it (time stands
/// still). Nothing: nothing will ever come, so time jumps to the deadline and
/// the attempt has timed out, exactly `timeout_s` after it began.
class FakeClock final : public udp::Clock {
 public:
  /// Datagrams sent to the device and not yet read by it, counted once the
  /// server has handled everything the device sent.
  using InFlight = std::function<int64_t()>;

  int64_t NowNs() override { return now_ns_; }
  WaitResult WaitReadable(int fd, int64_t deadline_ns) override {
    if (now_ns_ >= deadline_ns) return WaitResult::kNotYet;
    if (in_flight_ && in_flight_() > 0) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(kFaultAfter_s * 1000)) > 0) return WaitResult::kReadable;
      FAIL_CHECK("FakeClock: a datagram sent to the device never arrived");
    }
    now_ns_ = deadline_ns;
    return WaitResult::kNotYet;
  }
  /// The device slept or computed for `ns` (between calls).
  void Advance(int64_t ns) { now_ns_ += ns; }
  void set_in_flight(InFlight in_flight) { in_flight_ = std::move(in_flight); }

 private:
  int64_t now_ns_ = 0;
  InFlight in_flight_;
};

/// A udp device configuration for loopback servers (port 0: side absent).
/// The defaults are for the real clock: a loaded test machine must not turn
/// replies into timeouts.
DeviceConfig LoopbackConfig(int left_port, int right_port, double timeout_s = 5.0, int retries = 1,
                            double lost_after_s = 60.0) {
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

/// The left arm's fake server and a device on a FakeClock that sees what is
/// on the wire between them. Drive it from the test's thread only.
struct Rig {
  explicit Rig(double timeout_s = 0.25, int retries = 1, double lost_after_s = 1.0)
      : arm(Side::kLeft),
        device(LoopbackConfig(arm.port(), 0, timeout_s, retries, lost_after_s), clock) {
    clock.set_in_flight([this]() -> int64_t {
      const UdpCounters c = device.Counters(Side::kLeft);
      if (!arm.WaitHandled(Sent(c))) FAIL_CHECK("the fake arm never got what the device sent");
      if (c.socket_errors != 0) FAIL_CHECK("socket errors against the fake arm");
      return static_cast<int64_t>(arm.sent()) - static_cast<int64_t>(Received(c));
    });
  }
  UdpCounters counters() const { return device.Counters(Side::kLeft); }

  FakeArm arm;
  FakeClock clock;
  UdpDevice device;
};

}  // namespace

TEST_CASE("udp::MonotonicClock: a wait ends with data, or at once past its deadline",
          "[udp][clock]") {
  udp::Clock& clock = udp::SystemClock();
  int fds[2];
  REQUIRE(::socketpair(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0, fds) == 0);
  const udp::UniqueFd a(fds[0]);
  const udp::UniqueFd b(fds[1]);
  const int64_t now = clock.NowNs();
  CHECK(clock.NowNs() >= now);
  // A deadline already passed: no wait at all.
  CHECK(clock.WaitReadable(a.get(), now) == udp::Clock::WaitResult::kNotYet);
  const uint8_t byte = 1;
  REQUIRE(::send(b.get(), &byte, 1, 0) == 1);
  // Data already queued: readable long before this deadline only a fault reaches.
  CHECK(clock.WaitReadable(a.get(), clock.NowNs() + SToNs(kFaultAfter_s)) ==
        udp::Clock::WaitResult::kReadable);
}

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
  Rig rig;
  UdpDevice& device = rig.device;
  FakeArm& arm = rig.arm;
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
  REQUIRE(test::WaitFor([&] { return arm.seen().finger_forces == 1; }, kFaultAfter_s));
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

  const UdpCounters c = rig.counters();
  CHECK(c.requests == 4);
  CHECK(c.replies == 4);
  CHECK(c.forces_sent == 2);
  CHECK(c.timeouts == 0);
  CHECK(c.retries == 0);
  CHECK(c.stale == 0);
  CHECK(c.malformed_total() == 0);
  CHECK(device.Counters().requests == 4);  // both sides summed; right has none
  CHECK(rig.clock.NowNs() == 0);           // no wait ran to its deadline
}

TEST_CASE("udp device: invalid commands are sent as zero and counted", "[udp][device]") {
  Rig rig;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  rig.device.WriteWristForce(Side::kLeft, {1.0, nan, 1.0});
  rig.device.WriteFingerForces(Side::kLeft,
                               {1.0, -2.0, std::numeric_limits<double>::infinity(), 1.0, 1.0});
  REQUIRE(test::WaitFor([&] { return rig.arm.seen().finger_forces == 1; }, kFaultAfter_s));
  CHECK(rig.arm.seen().last_wrist_force == Vec3d{0, 0, 0});
  CHECK(rig.arm.seen().last_finger_force == std::array<double, kFingers>{1, 0, 0, 1, 1});
  CHECK(rig.counters().invalid_commands == 2);
}

TEST_CASE(
    "udp device: stale, out-of-order, malformed and mistyped replies are rejected and counted",
    "[udp][device]") {
  Rig rig;
  UdpDevice& device = rig.device;
  WristRaw raw;
  GloveRaw glove;

  SECTION("replies to other sequence numbers") {
    rig.arm.set_mode(FakeArm::Mode::kStaleFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    CHECK(raw.position[0] == 1.0);
    const UdpCounters c = rig.counters();
    CHECK(c.stale == 2);  // one older, one newer than the outstanding request
    CHECK(c.replies == 1);
  }
  SECTION("duplicates") {
    rig.arm.set_mode(FakeArm::Mode::kDuplicate);
    for (int i = 0; i < 5; ++i) REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    // Each duplicate is read (and rejected) by the next call at the latest.
    CHECK(rig.counters().stale == 4);
    CHECK(rig.counters().replies == 5);
  }
  SECTION("malformed datagrams") {
    rig.arm.set_mode(FakeArm::Mode::kGarbageFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    REQUIRE(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kOk);
    const UdpCounters c = rig.counters();
    CHECK(c.malformed[Idx(udp::DecodeStatus::kShort)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadMagic)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadVersion)] == 2);
    CHECK(c.malformed[Idx(udp::DecodeStatus::kBadChecksum)] == 2);
    CHECK(c.malformed_total() == 8);
    CHECK(c.replies == 2);
  }
  SECTION("the right sequence but the wrong type") {
    rig.arm.set_mode(FakeArm::Mode::kWrongTypeFirst);
    REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    REQUIRE(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kOk);
    CHECK(rig.counters().unexpected == 2);
  }
  // None of them cost a timeout: the valid reply behind them ends the wait.
  CHECK(rig.counters().timeouts == 0);
  CHECK(rig.clock.NowNs() == 0);
}

TEST_CASE("udp device: a reply from the other arm's server is not trusted", "[udp][device]") {
  // A server that answers a left-arm request as the right arm (the real
  // server answers ERROR wrong_side instead; see the server test below).
  Rig rig(0.1, 0);
  rig.arm.set_mode(FakeArm::Mode::kOtherSide);
  WristRaw raw;
  CHECK(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
  const UdpCounters c = rig.counters();
  CHECK(c.unexpected == 1);
  CHECK(c.replies == 0);
  CHECK(c.timeouts == 1);  // the forged reply did not end the wait
  CHECK(rig.clock.NowNs() == 100 * kMs);
}

TEST_CASE("udp device: timeouts and retries are counted", "[udp][device]") {
  Rig rig(0.05, 2, 30.0);
  WristRaw raw;
  SECTION("an answered retry") {
    rig.arm.set_mode(FakeArm::Mode::kDropFirstAttempt);
    REQUIRE(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
    const UdpCounters c = rig.counters();
    CHECK(c.timeouts == 1);
    CHECK(c.retries == 1);
    CHECK(c.unanswered == 0);
    CHECK(c.replies == 1);
    CHECK(rig.arm.seen().wrist_requests == 2);  // the same request, sent twice
    CHECK(rig.arm.seen().last_sequence == 1);
    CHECK(rig.clock.NowNs() == 50 * kMs);  // one timeout_s, then the answer
  }
  SECTION("silence") {
    rig.arm.set_mode(FakeArm::Mode::kSilent);
    CHECK(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
    const UdpCounters c = rig.counters();
    CHECK(c.timeouts == 3);  // 1 + retries
    CHECK(c.retries == 2);
    CHECK(c.unanswered == 1);
    CHECK(c.replies == 0);
    CHECK(rig.arm.seen().wrist_requests == 3);
    CHECK(rig.clock.NowNs() == 150 * kMs);  // worst case: (1 + retries) × timeout_s
    CHECK_FALSE(rig.device.Lost(Side::kLeft));
  }
  SECTION("ERROR busy ends the wait without a timeout") {
    rig.arm.set_mode(FakeArm::Mode::kErrorBusy);
    CHECK(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
    const UdpCounters c = rig.counters();
    CHECK(c.errors[Idx(udp::ErrorCode::kBusy)] == 1);
    CHECK(c.timeouts == 0);
    CHECK(c.retries == 0);
    CHECK(rig.clock.NowNs() == 0);
  }
}

TEST_CASE("udp device: silence turns a side lost after lost_after_s; answers bring it back",
          "[udp][device]") {
  // timeout 20 ms, 1 retry: a silent call costs 40 ms; lost after 300 ms.
  Rig rig(0.02, 1, 0.3);
  UdpDevice& device = rig.device;
  WristRaw raw;
  GloveRaw glove;
  REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);  // at 0 ms
  rig.arm.set_mode(FakeArm::Mode::kSilent);

  SECTION("counted from the last valid reply, call by call") {
    // Calls end at 40, 80, ..., 280 ms: no data, not yet lost.
    for (int call = 1; call <= 7; ++call) {
      INFO("silent call " << call);
      REQUIRE(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);
    }
    CHECK_FALSE(device.Lost(Side::kLeft));
    CHECK(device.WriteWristForce(Side::kLeft, {0, 0, 0}) == DeviceStatus::kOk);
    CHECK(rig.counters().lost_transitions == 0);
    // The 8th ends at 320 ms ≥ 300 ms: lost.
    CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);
    CHECK(rig.clock.NowNs() == 320 * kMs);
    const UdpCounters c = rig.counters();
    CHECK(c.timeouts == 16);
    CHECK(c.retries == 8);
    CHECK(c.unanswered == 8);
    CHECK(c.lost_transitions == 1);
  }
  SECTION("time that passes between calls counts too") {
    rig.clock.Advance(250 * kMs);  // the servo thread stalled, say
    CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kNoData);  // 290 ms
    CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);    // 330 ms
    CHECK(rig.counters().lost_transitions == 1);
  }

  CHECK(device.Lost(Side::kLeft));
  CHECK(device.WriteWristForce(Side::kLeft, {0, 0, 0}) == DeviceStatus::kLost);
  CHECK(device.WriteFingerForces(Side::kLeft, {0, 0, 0, 0, 0}) == DeviceStatus::kLost);
  // Lost stays lost, probed with one attempt per call (no retries): one timeout_s each.
  const UdpCounters before = rig.counters();
  const int64_t lost_at = rig.clock.NowNs();
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);
  CHECK(device.ReadGlove(Side::kLeft, 0, glove) == DeviceStatus::kLost);
  const UdpCounters after = rig.counters();
  CHECK(after.timeouts - before.timeouts == 2);
  CHECK(after.retries == before.retries);
  CHECK(after.lost_transitions == 1);
  CHECK(rig.clock.NowNs() - lost_at == 40 * kMs);

  rig.arm.set_mode(FakeArm::Mode::kNormal);
  CHECK(device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
  CHECK_FALSE(device.Lost(Side::kLeft));
  CHECK(rig.counters().recoveries == 1);
  CHECK(rig.counters().lost_transitions == 1);
  CHECK(device.WriteWristForce(Side::kLeft, {0, 0, 0}) == DeviceStatus::kOk);
}

TEST_CASE("udp device: no server on the port: no data, then lost, errors counted",
          "[udp][device]") {
  // Real sockets and the real clock: what matters here is what the kernel
  // reports for a port nobody listens on.
  int port = 0;
  {
    udp::UniqueFd closed = BoundLoopback(port);  // a port nobody listens on once this closes
  }
  UdpDevice device(LoopbackConfig(port, 0, 0.01, 0, 0.1));
  WristRaw raw;
  DeviceStatus status = DeviceStatus::kOk;
  REQUIRE(test::WaitFor(
      [&] { return (status = device.ReadWrist(Side::kLeft, 0, raw)) == DeviceStatus::kLost; },
      kFaultAfter_s));
  const UdpCounters c = device.Counters(Side::kLeft);
  CHECK(c.replies == 0);
  CHECK(c.unanswered == c.requests);
  CHECK(c.socket_errors > 0);  // ICMP port unreachable shows as ECONNREFUSED on a connected socket
  CHECK(c.lost_transitions == 1);
}

TEST_CASE("udp device: ERROR device_lost makes the side lost at once", "[udp][device]") {
  Rig rig(0.25, 1, 60.0);
  WristRaw raw;
  rig.arm.set_mode(FakeArm::Mode::kErrorDeviceLost);
  CHECK(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kLost);
  CHECK(rig.counters().errors[Idx(udp::ErrorCode::kDeviceLost)] == 1);
  CHECK(rig.counters().lost_transitions == 1);
  CHECK(rig.counters().timeouts == 0);
  CHECK(rig.clock.NowNs() == 0);  // no waiting for lost_after_s
  rig.arm.set_mode(FakeArm::Mode::kNormal);
  CHECK(rig.device.ReadWrist(Side::kLeft, 0, raw) == DeviceStatus::kOk);
  CHECK(rig.counters().recoveries == 1);
}

TEST_CASE("udp device: the servo calls allocate nothing, on good and bad paths",
          "[udp][device][alloc]") {
  // The real clock: its ppoll path is the one the servo thread runs. Nothing
  // here is counted but allocations, so late replies do not matter.
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
  // The real clock, shared by both sides' threads, with timeouts only a fault
  // reaches; a side stops at its first unanswered call.
  FakeArm left(Side::kLeft);
  FakeArm right(Side::kRight);
  UdpDevice device(LoopbackConfig(left.port(), right.port()));
  constexpr int kCycles = 500;
  std::array<int, kSides> ok{};
  std::array<bool, kSides> side_seen_right{};
  const auto drive = [&](Side side) {
    WristRaw raw;
    for (int i = 0; i < kCycles; ++i) {
      if (device.ReadWrist(side, i, raw) != DeviceStatus::kOk) break;
      ++ok[Index(side)];
      // The fake puts 10 × side in y: each side hears only its own server.
      side_seen_right[Index(side)] = raw.position[1] == 10.0 * Index(side);
      device.WriteWristForce(side, {static_cast<double>(Index(side)), 0, 0});
    }
  };
  {
    test::Thread a("left side", [&] { drive(Side::kLeft); });
    test::Thread b("right side", [&] { drive(Side::kRight); });
    a.Join();
    b.Join();
  }
  CHECK(ok[0] == kCycles);
  CHECK(ok[1] == kCycles);
  CHECK(side_seen_right[0]);
  CHECK(side_seen_right[1]);
  CHECK(device.Counters(Side::kLeft).replies == kCycles);
  CHECK(device.Counters(Side::kRight).replies == kCycles);
  REQUIRE(test::WaitFor([&] { return right.seen().wrist_forces == kCycles; }, kFaultAfter_s));
  CHECK(right.seen().last_wrist_force == Vec3d{1, 0, 0});
  CHECK(device.Counters().stale == 0);
  CHECK(device.Counters().timeouts == 0);
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
  // Several attempts of a second each: a flood (the garbage section below)
  // may make the server's socket drop a request, which a retry repairs.
  UdpDevice device(LoopbackConfig(left.port, right.port, 1.0, 4));

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
  {
    test::Thread a("left side", [&] { drive(Side::kLeft); });
    test::Thread b("right side", [&] { drive(Side::kRight); });
    a.Join();
    b.Join();
  }
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
    UdpDevice intruder(LoopbackConfig(left.port, 0, 5.0, 0));
    REQUIRE(device.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk);
    CHECK(intruder.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kNoData);
    CHECK(intruder.Counters().errors[Idx(udp::ErrorCode::kBusy)] == 1);
  }
  SECTION("an arm pointed at the other arm's server gets ERROR wrong_side") {
    UdpDevice swapped(LoopbackConfig(right.port, 0, 5.0, 0));
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
    UdpDevice first(LoopbackConfig(left.port, 0));
    REQUIRE(first.ReadWrist(Side::kLeft, MonotonicNs(), raw) == DeviceStatus::kOk);
    first.WriteWristForce(Side::kLeft, {2.0, 0, 0});
  }
  // Once the first client has been quiet for the watchdog time, another takes over.
  UdpDevice second(LoopbackConfig(left.port, 0, 5.0, 0));
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

TEST_CASE("udp device: refuses a config DeviceConfig::ValidateOrThrow refuses", "[udp][device]") {
  DeviceConfig c = LoopbackConfig(4000, 0);
  c.udp.timeout_s = 0.0;
  CHECK_THROWS_WITH(UdpDevice(c),
                    Catch::Contains("udp.timeout_s: expected a number in [1e-05, 5]"));
  c = LoopbackConfig(4000, 0);
  c.udp.retries = -1;
  CHECK_THROWS_AS(UdpDevice(c), ConfigFieldError);
  c = LoopbackConfig(4000, 0);
  c.driver = "sim";  // a valid config, for another driver
  CHECK_THROWS_WITH(UdpDevice(c), Catch::Contains("not udp"));
}
