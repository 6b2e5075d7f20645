// The link's fault injection: LinkFault's text form, and the FaultLine the
// fault transport feeds (loss, delay and jitter, the link-down switch),
// driven with hand-made packets into a receiver that records them.
#include <catch2/catch.hpp>

#include <algorithm>
#include <mutex>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/fault_transport.hpp"
#include "test_env.hpp"

using namespace haptel;
using eprosima::fastrtps::rtps::Locator_t;

namespace {

/// Records what reaches it: each packet's first byte pair as a number, and when.
class Recorder : public eprosima::fastdds::rtps::TransportReceiverInterface {
 public:
  void OnDataReceived(const eprosima::fastrtps::rtps::octet* data, const uint32_t size, const Locator_t&,
                      const Locator_t&) override {
    std::lock_guard lock(mutex_);
    REQUIRE(size == 2);
    ids_.push_back(data[0] | (data[1] << 8));
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

 private:
  mutable std::mutex mutex_;
  std::vector<int> ids_;
  std::vector<int64_t> at_ns_;
};

void Send(link::FaultLine& line, Recorder& to, int id) {
  const uint8_t data[2] = {static_cast<uint8_t>(id & 0xff), static_cast<uint8_t>(id >> 8)};
  line.Receive(&to, data, 2, Locator_t{}, Locator_t{});
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
  CHECK(what("delay=100") .find("not 'delay=100'") != std::string::npos);  // no unit
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
