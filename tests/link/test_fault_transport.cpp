// The link's fault injection: LinkFault's text form, the rate stage
// (RateQueue) on a clock of the test's own, and the FaultLine the fault
// transport feeds (loss, delay and jitter, rate and its queue, the link-down
// switch), driven with hand-made packets into a receiver that records them.
#include <algorithm>
#include <catch2/catch.hpp>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/fault_transport.hpp"
#include "test_env.hpp"

using namespace haptel;
using eprosima::fastrtps::rtps::Locator_t;

namespace {

/// Records what reaches it: each packet's first byte pair as a number, its size, and when.
class Recorder : public eprosima::fastdds::rtps::TransportReceiverInterface {
 public:
  void OnDataReceived(const eprosima::fastrtps::rtps::octet* data, const uint32_t size,
                      const Locator_t&, const Locator_t&) override {
    std::lock_guard lock(mutex_);
    REQUIRE(size >= 2);
    ids_.push_back(data[0] | (data[1] << 8));
    bytes_ += size;
    at_ns_.push_back(MonotonicNs());
  }
  size_t count() const {
    std::lock_guard lock(mutex_);
    return ids_.size();
  }
  std::vector<int> ids() const {
    std::lock_guard lock(mutex_);
    return ids_;
  }
  std::vector<int64_t> at_ns() const {
    std::lock_guard lock(mutex_);
    return at_ns_;
  }
  uint64_t bytes() const {
    std::lock_guard lock(mutex_);
    return bytes_;
  }

 private:
  mutable std::mutex mutex_;
  uint64_t bytes_ = 0;
  std::vector<int> ids_;
  std::vector<int64_t> at_ns_;
};

void Send(link::FaultLine& line, Recorder& to, int id, size_t bytes = 2) {
  std::vector<uint8_t> data(bytes, 0);
  data[0] = static_cast<uint8_t>(id & 0xff);
  data[1] = static_cast<uint8_t>(id >> 8);
  line.Receive(&to, data.data(), static_cast<uint32_t>(bytes), Locator_t{}, Locator_t{});
}

/// What ParseLinkFault says of `text` ("accepted" when it takes it).
std::string ParseError(const std::string& text) {
  try {
    ParseLinkFault(text);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

}  // namespace

TEST_CASE("link fault text: parsed in any order and units, written back, bad parts named") {
  const LinkFault f = ParseLinkFault("delay=100ms,jitter=20ms,loss=5%");
  CHECK(f.enabled);
  CHECK(f.delay_s == Approx(0.1));
  CHECK(f.jitter_s == Approx(0.02));
  CHECK(f.loss == Approx(0.05));
  const LinkFault g = ParseLinkFault("loss=0.1,delay=0.25s,jitter=500us");
  CHECK(g.delay_s == Approx(0.25));
  CHECK(g.jitter_s == Approx(0.0005));
  CHECK(g.loss == Approx(0.1));
  const LinkFault on = ParseLinkFault("on");
  CHECK(on.enabled);
  CHECK(on.delay_s == 0.0);
  CHECK(on.loss == 0.0);
  const LinkFault back = ParseLinkFault(LinkFaultText(f));
  CHECK(back.delay_s == Approx(f.delay_s));
  CHECK(back.jitter_s == Approx(f.jitter_s));
  CHECK(back.loss == Approx(f.loss));

  const auto what = [](const std::string& text) {
    try {
      ParseLinkFault(text);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  CHECK(what("delay=100").find("not 'delay=100'") != std::string::npos);  // no unit
  CHECK(what("delay=-5ms").find("a time >= 0") != std::string::npos);
  CHECK(what("loss=100%").find("a loss from 0 to 99%") != std::string::npos);
  CHECK(what("loss=abc").find("not 'loss=abc'") != std::string::npos);
  CHECK(what("lag=5ms").find("delay=TIME, jitter=TIME or loss=PERCENT") != std::string::npos);
  CHECK(what("delay=100ms,").find("not ''") != std::string::npos);
  CHECK(what("delay=20s").find("at most 10 s") != std::string::npos);
  try {
    ParseLinkFaultOption("loss=2");
    FAIL("accepted");
  } catch (const UsageError& e) {
    CHECK(std::string(e.what()).find("option --link-fault: expected a loss") == 0);
  }
}

TEST_CASE(
    "link fault text: a rate in kbit or Mbit and its queue, written back; the keys given override "
    "a base") {
  const LinkFault f = ParseLinkFault("rate=1Mbit,delay=40ms");
  CHECK(f.rate_bps == Approx(1e6));
  CHECK(f.queue_s == Approx(0.1));  // the default depth
  CHECK(f.delay_s == Approx(0.04));
  const LinkFault g = ParseLinkFault("queue=250ms,rate=500kbit");
  CHECK(g.rate_bps == Approx(5e5));
  CHECK(g.queue_s == Approx(0.25));
  CHECK(ParseLinkFault("rate=2.5mbit").rate_bps == Approx(2.5e6));  // tc's spelling
  const LinkFault back = ParseLinkFault(LinkFaultText(g));
  CHECK(back.rate_bps == Approx(g.rate_bps));
  CHECK(back.queue_s == Approx(g.queue_s));
  // Without a rate the text is as it always was (recorded runs compare equal).
  CHECK(LinkFaultText(ParseLinkFault("delay=100ms")) == "delay=0.1s,jitter=0s,loss=0");
  CHECK(ParseLinkFault("on").rate_bps == 0.0);

  LinkFault base = ParseLinkFault("rate=2Mbit,delay=30ms,jitter=8ms,loss=0.1%");
  const LinkFault over = ParseLinkFault("loss=5%,queue=50ms", base);
  CHECK(over.rate_bps == Approx(2e6));
  CHECK(over.delay_s == Approx(0.03));
  CHECK(over.jitter_s == Approx(0.008));
  CHECK(over.loss == Approx(0.05));
  CHECK(over.queue_s == Approx(0.05));
  CHECK(ParseLinkFault("on", base).rate_bps == Approx(2e6));
}

TEST_CASE("link fault text: a bad rate or queue says what was expected and names the part") {
  for (const char* bad :
       {"rate=0", "rate=-1Mbit", "rate=fast", "rate=1", "rate=1Mbps", "rate=20Gbit"}) {
    INFO(bad);
    const std::string what = ParseError(bad);
    CHECK(what.find("a rate from 1kbit to 10Gbit with its unit, such as 1Mbit or 500kbit") == 0);
    CHECK(what.find(std::string("(not '") + bad + "')") != std::string::npos);
  }
  for (const char* bad : {"rate=1Mbit,queue=abc", "rate=1Mbit,queue=0", "rate=1Mbit,queue=0ms",
                          "rate=1Mbit,queue=11s"}) {
    INFO(bad);
    CHECK(ParseError(bad).find("a queue depth from 1ms to 10s with its unit, such as 100ms") == 0);
  }
  CHECK(ParseError("queue=100ms").find("queue=TIME only with a rate=RATE") == 0);
  CHECK(ParseError("speed=1Mbit").find("rate=RATE, queue=TIME, delay=TIME") == 0);
  try {
    ParseLinkFaultOption("rate=0");
    FAIL("accepted");
  } catch (const UsageError& e) {
    CHECK(std::string(e.what()).find("option --link-fault: expected a rate") == 0);
  }
  LinkFault built;
  built.rate_bps = 10.0;  // built in code, below the least rate
  CHECK_THROWS_AS(built.ValidateOrThrow(), ConfigFieldError);
}

TEST_CASE("rate queue: what it passes over time is its rate, whatever is offered") {
  // 1 Mbit/s offered 1000-byte packets at twice that for 10 s of the test's own clock.
  const double rate_bps = 1e6;
  link::RateQueue queue(rate_bps, 0.1);
  const int64_t gap_ns = 4'000'000;  // 8000 bit every 4 ms: 2 Mbit/s
  uint64_t passed_bytes = 0, dropped = 0;
  int64_t last_passed_ns = 0;
  for (int64_t now = 0; now < SToNs(10.0); now += gap_ns) {
    const std::optional<int64_t> passed = queue.Admit(now, 1000);
    if (!passed) {
      ++dropped;
      continue;
    }
    CHECK(*passed >= last_passed_ns + 8'000'000);    // one after the other, 8 ms each
    CHECK(*passed - now <= SToNs(0.1) + 8'000'000);  // never queued past its depth
    last_passed_ns = *passed;
    passed_bytes += 1000;
  }
  const double seconds = NsToS(last_passed_ns);
  CHECK(passed_bytes * 8.0 / seconds == Approx(rate_bps).epsilon(0.01));
  CHECK(dropped ==
        Approx(1250.0).epsilon(0.02));  // half of 2500 offered, less the queue's 12 or so

  SECTION("below its rate nothing waits and nothing is dropped") {
    link::RateQueue idle(rate_bps, 0.1);
    for (int64_t now = 0; now < SToNs(1.0); now += 20'000'000) {
      const std::optional<int64_t> passed = idle.Admit(now, 1000);
      REQUIRE(passed);
      CHECK(*passed == now + 8'000'000);
    }
  }
}

TEST_CASE(
    "rate queue: a burst deeper than the queue is cut at its depth (drop-tail), then served "
    "again") {
  link::RateQueue queue(1e6, 0.1);  // 1000 bytes take 8 ms: 100 ms holds 12 behind the first
  int admitted = 0;
  for (int i = 0; i < 100; ++i) admitted += queue.Admit(0, 1000) ? 1 : 0;
  CHECK(admitted == 13);
  CHECK(queue.WaitNs(0) == 13 * 8'000'000);
  // Once it has drained it takes packets again.
  CHECK(queue.Admit(SToNs(0.2), 1000));
}

TEST_CASE(
    "rate queue: commands and states go ahead of a saturated video queue, and take their share of "
    "the rate") {
  link::RateQueue queue(1e6, 0.1);  // 1 Mbit/s: 1000 bytes take 8 ms
  // Video: 12 kilobyte packets at once, 96 ms of backlog.
  for (int i = 0; i < 12; ++i) REQUIRE(queue.Admit(0, 1000));
  const int64_t video_done = queue.WaitNs(0);
  CHECK(video_done == 96'000'000);
  // A 200-byte command arriving now waits for at most one MTU (12 ms) of
  // the video on the wire, then its own 1.6 ms: not for the whole backlog.
  const std::optional<int64_t> command = queue.Admit(0, 200);
  REQUIRE(command);
  CHECK(*command == 12'000'000 + 1'600'000);
  // A state right behind it queues behind the command, not the video.
  const std::optional<int64_t> state = queue.Admit(0, 300);
  REQUIRE(state);
  CHECK(*state == *command + 2'400'000);
  // What they took, the video behind them loses: the next video packet
  // starts after the backlog plus their 4 ms.
  CHECK(queue.WaitNs(0) == 96'000'000 + 4'000'000);
  const std::optional<int64_t> next_video = queue.Admit(0, 1000);
  REQUIRE(next_video);  // exactly at the queue's 100 ms depth: still taken
  CHECK(*next_video == 96'000'000 + 4'000'000 + 8'000'000);
  CHECK_FALSE(queue.Admit(0, 1000));  // past it: dropped
  // Over a saturated second both classes together pass the rate, no more.
  link::RateQueue busy(1e6, 0.1);
  uint64_t passed = 0;
  int64_t last = 0;
  for (int64_t now = 0; now < SToNs(1.0); now += 1'000'000) {
    for (const size_t bytes : {size_t{1000}, size_t{1000}, size_t{100}}) {  // 16.8 Mbit/s offered
      if (const std::optional<int64_t> t = busy.Admit(now, bytes)) {
        passed += bytes;
        last = std::max(last, *t);
      }
    }
  }
  CHECK(passed * 8.0 / NsToS(last) <= 1e6 * 1.02);
  CHECK(passed * 8.0 / NsToS(last) >= 1e6 * 0.95);
}

TEST_CASE("fault line: loss drops its share of the packets, the rest arrive at once and in order") {
  link::FaultLine line(ParseLinkFault("loss=25%"), 7);
  Recorder to;
  for (int i = 0; i < 4000; ++i) Send(line, to, i);
  const link::FaultCounts c = line.Counts();
  CHECK(c.received == 4000);
  CHECK(c.lost + to.count() == 4000);
  CHECK(c.lost > 850);  // 1000 expected; 5 standard deviations is 137
  CHECK(c.lost < 1150);
  const std::vector<int> ids = to.ids();
  CHECK(std::is_sorted(ids.begin(), ids.end()));
  CHECK(c.delayed == 0);
}

TEST_CASE("fault line: delayed packets arrive no earlier than their delay; jitter reorders them") {
  SECTION("delay only: each late by at least the delay, all in order") {
    link::FaultLine line(ParseLinkFault("delay=30ms"), 1);
    Recorder to;
    std::vector<int64_t> sent_ns;
    for (int i = 0; i < 20; ++i) {
      sent_ns.push_back(MonotonicNs());
      Send(line, to, i);
    }
    REQUIRE(test::WaitFor([&] { return to.count() == 20; }, 10.0));
    const std::vector<int> ids = to.ids();
    const std::vector<int64_t> at = to.at_ns();
    for (size_t k = 0; k < ids.size(); ++k) {
      CHECK(at[k] - sent_ns[static_cast<size_t>(ids[k])] >= SToNs(0.030));
    }
    CHECK(std::is_sorted(ids.begin(), ids.end()));
    CHECK(line.Counts().delayed == 20);
  }
  SECTION("jitter: delays spread over delay ± jitter, so some overtake others") {
    link::FaultLine line(ParseLinkFault("delay=40ms,jitter=39ms"), 2);
    Recorder to;
    const int64_t start = MonotonicNs();
    for (int i = 0; i < 200; ++i) Send(line, to, i);
    REQUIRE(test::WaitFor([&] { return to.count() == 200; }, 10.0));
    const std::vector<int> ids = to.ids();
    CHECK_FALSE(std::is_sorted(ids.begin(), ids.end()));
    for (const int64_t at : to.at_ns()) CHECK(at - start >= SToNs(0.001));
  }
}

TEST_CASE(
    "fault line: a rate delivers a burst at that rate, in order, and counts what its full queue "
    "drops") {
  // 1250-byte packets take 10 ms each at 1 Mbit/s; a 100 ms queue holds about 10 behind the first.
  link::FaultLine line(ParseLinkFault("rate=1Mbit,queue=100ms"), 5);
  Recorder to;
  const int64_t start = MonotonicNs();
  for (int i = 0; i < 60; ++i) Send(line, to, i, 1250);
  const link::FaultCounts sent = line.Counts();
  CHECK(sent.queue_dropped >= 40);  // more pass only if sending the burst took over 100 ms
  CHECK(sent.queue_dropped_bytes == sent.queue_dropped * 1250);
  const size_t passing = 60 - sent.queue_dropped;
  REQUIRE(test::WaitFor([&] { return to.count() == passing; }, 10.0));
  const std::vector<int> ids = to.ids();
  CHECK(std::is_sorted(ids.begin(), ids.end()));
  CHECK(ids.front() == 0);
  // None arrives before its turn at the rate: the k-th after k + 1 packets' time.
  const std::vector<int64_t> at = to.at_ns();
  for (size_t k = 0; k < at.size(); ++k)
    CHECK(at[k] - start >= static_cast<int64_t>(k + 1) * 10'000'000);
  CHECK(line.Counts().delayed == passing);
  CHECK(to.bytes() == passing * 1250);
}

TEST_CASE(
    "rate queue: a rate changed at run time serves what comes next at the new rate, the queued at "
    "the old") {
  link::RateQueue queue(1e6, 0.1);  // 1000 bytes take 8 ms
  const int64_t first = *queue.Admit(0, 1000);
  CHECK(first == 8'000'000);
  queue.SetRate(0.5e6);  // now 16 ms
  CHECK(queue.rate_bps() == Approx(0.5e6));
  CHECK(*queue.Admit(0, 1000) == 8'000'000 + 16'000'000);  // behind the first, at the new rate
  CHECK(*queue.Admit(100'000'000, 1000) == 116'000'000);   // an idle link: its own 16 ms
}

TEST_CASE(
    "fault line: its rate changes at run time, is added to a line without one, and is lifted by "
    "0") {
  link::FaultLine line(ParseLinkFault("on"), 6);  // no rate: everything at once
  CHECK(line.rate_bps() == 0.0);
  Recorder to;
  for (int i = 0; i < 20; ++i) Send(line, to, i, 1250);
  CHECK(to.count() == 20);
  // 1 Mbit/s: 1250-byte packets take 10 ms each, the 100 ms queue holds about 10.
  line.SetRate(1e6);
  CHECK(line.rate_bps() == Approx(1e6));
  for (int i = 0; i < 60; ++i) Send(line, to, 100 + i, 1250);
  CHECK(line.Counts().queue_dropped >= 40);
  REQUIRE(test::WaitFor([&] { return to.count() == 20 + 60 - line.Counts().queue_dropped; }, 10.0));
  line.SetRate(0.0);
  CHECK(line.rate_bps() == 0.0);
  const uint64_t dropped = line.Counts().queue_dropped;
  const size_t before = to.count();
  for (int i = 0; i < 60; ++i) Send(line, to, 200 + i, 1250);
  CHECK(to.count() == before + 60);  // no queue any more: delivered at once
  CHECK(line.Counts().queue_dropped == dropped);
  CHECK_THROWS_WITH(line.SetRate(-1.0), Catch::Contains("expected 0 (no limit) or more"));
}

TEST_CASE("fault line: the link-down switch drops everything both ways until it is restored") {
  link::FaultLine line(ParseLinkFault("on"), 3);
  Recorder to;
  Send(line, to, 1);
  CHECK(to.count() == 1);
  CHECK_FALSE(line.DropSend());
  link::SetLinkDown(true);
  Send(line, to, 2);
  const bool dropped_out = line.DropSend();
  link::SetLinkDown(false);
  CHECK(dropped_out);
  CHECK(to.count() == 1);
  CHECK(line.Counts().dropped_down == 2);
  Send(line, to, 3);
  CHECK(to.ids() == std::vector<int>{1, 3});
}

TEST_CASE("fault line: shut down, it drops what is queued and delivers nothing more") {
  link::FaultLine line(ParseLinkFault("delay=10s"), 4);
  Recorder to;
  for (int i = 0; i < 5; ++i) Send(line, to, i);
  line.Shutdown();
  Send(line, to, 9);
  CHECK(to.count() == 0);
  line.Shutdown();  // idempotent
}
