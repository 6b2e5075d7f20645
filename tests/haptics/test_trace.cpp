#include <atomic>
#include <catch2/catch.hpp>
#include <cstdio>
#include <thread>

#include "haptel/config/error.hpp"
#include "haptel/core/spsc_ring.hpp"
#include "haptel/haptics/device_factory.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/trace.hpp"
#include "scripted_device.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;
WristRaw Wrist(int64_t t, double x) {
  WristRaw w;
  w.t_ns = t;
  w.position = {x, 2 * x, 3 * x};
  return w;
}
}  // namespace

TEST_CASE("the SPSC ring keeps order, refuses when full, and survives a concurrent producer") {
  SpscRing<int> ring(3);  // rounds up to 4
  CHECK(ring.capacity() == 4);
  for (int i = 0; i < 4; ++i) CHECK(ring.Push(i));
  CHECK_FALSE(ring.Push(99));
  int v = -1;
  for (int i = 0; i < 4; ++i) {
    REQUIRE(ring.Pop(v));
    CHECK(v == i);
  }
  CHECK_FALSE(ring.Pop(v));

  SpscRing<uint64_t> big(64);
  constexpr uint64_t kCount = 200000;
  // A ring that loses or withholds an item would leave both loops spinning:
  // they give up at a deadline and the test fails instead of hanging.
  std::atomic<bool> give_up{false};
  test::Thread producer("producer", [&] {
    for (uint64_t i = 1; i <= kCount && !give_up.load(std::memory_order_relaxed);) {
      if (big.Push(i)) ++i;
    }
  });
  uint64_t expected = 1;
  bool in_order = true;
  const test::Deadline deadline(60.0);
  while (expected <= kCount && !deadline.passed()) {
    uint64_t got = 0;
    if (big.Pop(got)) {
      in_order &= got == expected;
      ++expected;
    }
  }
  give_up = true;
  producer.Join();
  CHECK(expected == kCount + 1);  // every item came out
  CHECK(in_order);
}

TEST_CASE("a trace written by the servo loop reads back record for record") {
  const auto dir = test::ScratchDir("trace");
  const auto file = dir / "session.trace";
  test::ScriptedDevice dev(true, true);
  Hal hal;
  DeviceConfig c;
  c.servo.slow_channel_divider = 5;
  {
    TraceWriter writer(file);
    ServoLoop loop(dev, hal, c, DeviceCalibration{});
    loop.SetTrace(&writer);
    for (int i = 1; i <= 20; ++i) {
      dev.position[0] = {double(i), 0, 0};
      dev.position[1] = {0, double(i), 0};
      loop.Tick(Side::kLeft, i * kMs);
      loop.Tick(Side::kRight, i * kMs);
    }
  }  // the writer drains and closes
  const auto records = ReadTrace(file);
  size_t wrists = 0;
  size_t gloves = 0;
  for (const auto& r : records) (r.kind == TraceRecord::kWrist ? wrists : gloves)++;
  CHECK(wrists == 40);
  CHECK(gloves == 8);  // every 5th of 20 cycles, both sides
  for (size_t i = 1; i < records.size(); ++i) CHECK(records[i].t_ns >= records[i - 1].t_ns);
  const auto& last = records.back();
  CHECK(last.t_ns == 20 * kMs);
  const WristRaw w = last.ToWrist();
  CHECK((last.side == 0 ? w.position[0] : w.position[1]) == 20.0);
}

TEST_CASE("a damaged trace is refused with the file and record named") {
  const auto dir = test::ScratchDir("trace-bad");
  const auto file = dir / "bad.trace";
  {
    TraceWriter writer(file);
    writer.Push(TraceRecord::FromWrist(Side::kLeft, Wrist(1, 1)));
  }
  std::filesystem::resize_file(file, std::filesystem::file_size(file) - 3);
  try {
    ReadTrace(file);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("bad.trace") != std::string::npos);
    CHECK(std::string(e.what()).find("record 0") != std::string::npos);
  }
  std::FILE* f = std::fopen(file.c_str(), "wb");
  std::fputs("not a trace at all", f);
  std::fclose(f);
  CHECK_THROWS_WITH(ReadTrace(file), Catch::Contains("bad header"));
}

TEST_CASE("replay plays a trace at its original timing, per side") {
  std::vector<TraceRecord> recs;
  for (int i = 0; i < 5; ++i) {
    recs.push_back(TraceRecord::FromWrist(Side::kRight, Wrist(1000 * kMs + i * 10 * kMs, i)));
    recs.push_back(
        TraceRecord::FromWrist(Side::kLeft, Wrist(1000 * kMs + i * 10 * kMs + 5 * kMs, 100 + i)));
  }
  ReplayDevice replay(recs, DeviceDescription{}, false);
  WristRaw w;
  const int64_t start = 7 * kMs;  // any clock: timing is relative to the first read
  REQUIRE(replay.ReadWrist(Side::kRight, start, w) == DeviceStatus::kOk);
  CHECK(w.position[0] == 0.0);
  CHECK(replay.ReadWrist(Side::kLeft, start + 4 * kMs, w) == DeviceStatus::kNoData);  // not due yet
  REQUIRE(replay.ReadWrist(Side::kLeft, start + 6 * kMs, w) == DeviceStatus::kOk);
  CHECK(w.position[0] == 100.0);
  replay.ReadWrist(Side::kRight, start + 25 * kMs, w);
  CHECK(w.position[0] == 2.0);
  replay.ReadWrist(Side::kRight, start + 1000 * kMs, w);  // past the end: the last sample
  CHECK(w.position[0] == 4.0);
  CHECK(replay.WriteWristForce(Side::kRight, {1, 2, 3}) == DeviceStatus::kOk);
  CHECK(replay.commands_ignored(Side::kRight) == 1);
}

TEST_CASE(
    "a trace carries the session's engaged decisions, and replay says the hand is held or "
    "released as they say, released at the end") {
  const auto dir = test::ScratchDir("trace-engaged");
  const auto file = dir / "engaged.trace";
  {
    TraceWriter writer(file);
    writer.PushEngaged(1000 * kMs, true);  // the session's ring: both sides
    for (int i = 0; i < 50; ++i) {
      const int64_t t = 1000 * kMs + i * 10 * kMs;
      writer.Push(TraceRecord::FromWrist(Side::kLeft, Wrist(t, i)));
      writer.Push(TraceRecord::FromWrist(Side::kRight, Wrist(t, i)));
    }
    writer.PushEngaged(1200 * kMs, false);
    writer.PushEngaged(1300 * kMs, true);
  }
  const auto records = ReadTrace(file);
  size_t engaged_records = 0;
  for (const auto& r : records) engaged_records += r.kind == TraceRecord::kEngaged;
  CHECK(engaged_records == 6);
  for (size_t i = 1; i < records.size(); ++i) CHECK(records[i].t_ns >= records[i - 1].t_ns);

  ReplayDevice replay(records, DeviceDescription{}, false);
  WristRaw w;
  const int64_t start = 3 * kMs;
  CHECK(replay.Presence(Side::kRight) == HandPresence::kHeld);  // nothing played yet
  REQUIRE(replay.ReadWrist(Side::kRight, start, w) == DeviceStatus::kOk);
  CHECK(replay.Presence(Side::kRight) == HandPresence::kHeld);
  // 1.5 s and more after the first read: still held as recorded, though a
  // still hand would be judged gone from its motion.
  replay.ReadWrist(Side::kRight, start + 150 * kMs, w);
  CHECK(replay.Presence(Side::kRight) == HandPresence::kHeld);
  replay.ReadWrist(Side::kRight, start + 250 * kMs, w);
  CHECK(replay.Presence(Side::kRight) == HandPresence::kReleased);
  replay.ReadWrist(Side::kLeft, start + 250 * kMs, w);
  CHECK(replay.Presence(Side::kLeft) == HandPresence::kReleased);
  replay.ReadWrist(Side::kRight, start + 350 * kMs, w);
  CHECK(replay.Presence(Side::kRight) == HandPresence::kHeld);
  replay.ReadWrist(Side::kRight, start + 600 * kMs, w);  // past the end: the hand is gone
  CHECK(replay.Presence(Side::kRight) == HandPresence::kReleased);

  // A trace without them: the session judges from the motion after the first second.
  std::vector<TraceRecord> bare;
  for (const auto& r : records)
    if (r.kind != TraceRecord::kEngaged) bare.push_back(r);
  ReplayDevice judged(bare, DeviceDescription{}, false);
  judged.ReadWrist(Side::kRight, start, w);
  CHECK(judged.Presence(Side::kRight) == HandPresence::kHeld);
  judged.ReadWrist(Side::kRight, start + 1100 * kMs, w);
  CHECK(judged.Presence(Side::kRight) == HandPresence::kUnknown);
}

TEST_CASE("replay can loop") {
  std::vector<TraceRecord> recs;
  for (int i = 0; i < 4; ++i)
    recs.push_back(TraceRecord::FromWrist(Side::kRight, Wrist(i * 10 * kMs, i)));
  ReplayDevice replay(recs, DeviceDescription{}, true);
  WristRaw w;
  replay.ReadWrist(Side::kRight, 1, w);
  replay.ReadWrist(Side::kRight, 1 + 30 * kMs, w);
  CHECK(w.position[0] == 3.0);
  replay.ReadWrist(Side::kRight, 1 + 31 * kMs + 15 * kMs, w);  // 46 ms: second round, 15 ms in
  CHECK(w.position[0] == 1.0);
}

TEST_CASE("the replay driver opens from a device file, and a bad trace names the file and key") {
  const auto dir = test::ScratchDir("replay-config");
  {
    TraceWriter writer(dir / "t.trace");
    for (int i = 0; i < 10; ++i)
      writer.Push(TraceRecord::FromWrist(Side::kRight, Wrist(i * kMs, i)));
  }
  std::FILE* f = std::fopen((dir / "replay.yaml").c_str(), "w");
  std::fputs("name: r\ndriver: replay\nsides: [right]\nreplay: {trace: t.trace}\n", f);
  std::fclose(f);
  auto device = MakeDevice(LoadDevice(dir / "replay.yaml"));
  WristRaw w;
  CHECK(device->ReadWrist(Side::kRight, 1, w) == DeviceStatus::kOk);
  CHECK_FALSE(device->HasSide(Side::kLeft));
  std::filesystem::resize_file(dir / "t.trace", 3);
  try {
    MakeDevice(LoadDevice(dir / "replay.yaml"));
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).find("replay.yaml") != std::string::npos);
    CHECK(std::string(e.what()).find("replay.trace") != std::string::npos);
  }
}

TEST_CASE(
    "MakeDevice refuses a config DeviceConfig::ValidateOrThrow refuses, whatever the driver") {
  DeviceConfig c;
  c.driver = "replay";  // and no trace
  CHECK_THROWS_WITH(MakeDevice(c), Catch::Contains("replay.trace"));
  c = DeviceConfig{};
  c.driver = "serial";
  CHECK_THROWS_AS(MakeDevice(c), ConfigFieldError);
}
