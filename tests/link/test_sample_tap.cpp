// The tap a session file records the link through (link/sample_tap.hpp):
// a writer's sample as it serialized it, a reader's as re-serialized from
// what DDS decoded, are the same bytes (so a session file holds what
// crossed the link), each on the channel its topic was given; a channel
// that wants no bytes gets the decoded sample alone.
#include <catch2/catch.hpp>
#include <mutex>
#include <vector>

#include "haptel/link/topic.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::link;

namespace {

/// Keeps what it is given: the topics (channel = index) and each sample's bytes.
class KeepingTap final : public SampleTap {
 public:
  explicit KeepingTap(bool bytes) : bytes_(bytes) {}
  int OnTopic(const std::string& topic, const std::string& type, TapDirection direction) override {
    std::lock_guard lock(mutex);
    topics.push_back({topic, type, direction});
    return static_cast<int>(topics.size()) - 1;
  }
  bool WantsBytes(int) const override { return bytes_; }
  void OnSample(int channel, int64_t now_ns, const void* sample, const uint8_t* cdr,
                size_t size) override {
    std::lock_guard lock(mutex);
    samples.push_back({channel, now_ns, sample != nullptr, std::vector<uint8_t>(cdr, cdr + size)});
  }
  struct Topic {
    std::string name, type;
    TapDirection direction;
  };
  struct Sample {
    int channel;
    int64_t now_ns;
    bool typed;
    std::vector<uint8_t> cdr;
  };
  std::mutex mutex;
  std::vector<Topic> topics;
  std::vector<Sample> samples;

 private:
  bool bytes_;
};

}  // namespace

TEST_CASE("a tapped sample's bytes are the same sent and received: what crossed the link") {
  LinkConfig config;
  config.domain_id = test::UniqueDomain(37);
  Participant a(config, "tap-a");
  Participant b(config, "tap-b");
  KeepingTap sent(true), received(true);
  a.SetTap(&sent);
  b.SetTap(&received);
  StateReader reader(b, TopicName("t", "state"), Profile::kState, [](const msg::VehicleState&) {});
  StateWriter writer(a, TopicName("t", "state"), Profile::kState);
  {
    std::lock_guard lock(sent.mutex);
    REQUIRE(sent.topics.size() == 1);
    CHECK(sent.topics[0].name == "haptel/t/state");
    CHECK(sent.topics[0].type == "haptel::msg::VehicleState");
    CHECK(sent.topics[0].direction == TapDirection::kSent);
    CHECK(received.topics[0].direction == TapDirection::kReceived);
  }
  REQUIRE(test::WaitFor([&] { return writer.matched() > 0 && reader.matched() > 0; }, 20.0));
  // Every kind of field: strings, a bounded sequence, an array, odd sizes.
  msg::VehicleState s;
  s.seq(7);
  s.speed(0.5f);
  s.bumper_left(true);
  s.motor_left_level(-3);
  s.fault_message("a fault of some length");
  s.owner("operator");
  s.ranges({1.0f, 2.5f, 3.25f});
  s.owner_writer()[3] = 9;
  s.vehicle_host("host");
  REQUIRE(writer.Write(s));
  REQUIRE(test::WaitFor(
      [&] {
        std::lock_guard lock(received.mutex);
        return !received.samples.empty();
      },
      10.0));
  std::lock_guard lock_sent(sent.mutex);
  std::lock_guard lock_received(received.mutex);
  REQUIRE(sent.samples.size() == 1);
  REQUIRE(received.samples.size() == 1);
  CHECK(sent.samples[0].cdr.size() > 4);
  CHECK(sent.samples[0].cdr[1] == 0x01);  // CDR, little-endian: the encapsulation header
  CHECK(received.samples[0].cdr == sent.samples[0].cdr);
  CHECK(received.samples[0].typed);
}

TEST_CASE("a channel that wants no bytes gets the decoded sample alone; no tap, nothing") {
  LinkConfig config;
  config.domain_id = test::UniqueDomain(38);
  Participant a(config, "tap-c");
  KeepingTap tap(false);
  TreadCommandWriter untapped(a, TopicName("t", "command"), Profile::kCommand);
  a.SetTap(&tap);
  TreadCommandWriter writer(a, TopicName("u", "command"), Profile::kCommand);
  msg::TreadCommand c;
  untapped.Write(c);
  writer.Write(c);
  std::lock_guard lock(tap.mutex);
  REQUIRE(tap.topics.size() == 1);  // made before the tap: never told
  REQUIRE(tap.samples.size() == 1);
  CHECK(tap.samples[0].typed);
  CHECK(tap.samples[0].cdr.empty());
}
