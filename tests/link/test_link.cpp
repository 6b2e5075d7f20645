#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <mutex>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/security.hpp"
#include "haptel/link/topic.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::link;

namespace {
LinkConfig Config(int salt) {
  LinkConfig c;
  c.domain_id = test::UniqueDomain(salt);
  return c;
}
}  // namespace

TEST_CASE("topic names carry the vehicle name") {
  CHECK(TopicName("robot1", "command") == "haptel/robot1/command");
  CHECK(TopicName("blimp", "video") == "haptel/blimp/video");
}

TEST_CASE("each camera has its own topics; the driven camera keeps the single camera's") {
  CHECK(VideoTopic("blimp", "pilot", true) == "haptel/blimp/video");
  CHECK(VideoFeedbackTopic("blimp", "pilot", true) == "haptel/blimp/video_feedback");
  CHECK(VideoTopic("blimp", "surveillance", false) == "haptel/blimp/video/surveillance");
  CHECK(VideoFeedbackTopic("blimp", "surveillance", false) ==
        "haptel/blimp/video_feedback/surveillance");
  CHECK(CameraCommandTopic("blimp", "surveillance") == "haptel/blimp/camera/surveillance");
  CHECK(CameraStatusTopic("blimp") == "haptel/blimp/cameras");
}

TEST_CASE("a camera command decodes for its own camera within its ranges only") {
  const CameraRange range{
      .pan_min = -3.0, .pan_max = 3.0, .tilt_min = -1.5, .tilt_max = 0.2, .zoom_max = 10.0};
  msg::CameraCommand m;
  CameraMessages::Encode("surveillance", {0.5, -0.25, 4.0}, m);
  CameraAim aim;
  REQUIRE(CameraMessages::Decode(m, "surveillance", range, aim));
  CHECK(aim.pan == Approx(0.5));
  CHECK(aim.tilt == Approx(-0.25));
  CHECK(aim.zoom == Approx(4.0));
  CHECK_FALSE(CameraMessages::Decode(m, "pilot", range, aim));  // another camera's topic
  m.zoom(12.0F);
  CHECK_FALSE(CameraMessages::Decode(m, "surveillance", range, aim));
  CHECK(aim.zoom == Approx(10.0));  // clamped, for whoever uses it anyway
  m.zoom(0.5F);
  CHECK_FALSE(CameraMessages::Decode(m, "surveillance", range, aim));
  m.zoom(1.0F);
  m.tilt(std::nanf(""));
  CHECK_FALSE(CameraMessages::Decode(m, "surveillance", range, aim));
  m.tilt(0.2005F);  // a float's rounding past the end
  CHECK(CameraMessages::Decode(m, "surveillance", range, aim));
}

TEST_CASE("a zoomed lens narrows its field of view by the tangent") {
  CHECK(ZoomedFovDeg(60.0, 1.0) == Approx(60.0));
  CHECK(ZoomedFovDeg(60.0, 10.0) == Approx(6.61).epsilon(0.01));
  CHECK(ZoomedFovDeg(60.0, 0.5) == Approx(60.0));  // never wider than the widest
}

TEST_CASE("QoS profiles: command best effort with a deadline, state reliable, video best effort") {
  LinkConfig c;
  c.command_deadline_s = 0.1;
  namespace dds = eprosima::fastdds::dds;
  const auto cmd = DataWriterQosFor(Profile::kCommand, c);
  CHECK(cmd.reliability().kind == dds::BEST_EFFORT_RELIABILITY_QOS);
  CHECK(cmd.history().depth == 1);
  CHECK(cmd.deadline().period.seconds == 0);
  CHECK(cmd.deadline().period.nanosec == 100'000'000U);
  CHECK(DataReaderQosFor(Profile::kState, c).reliability().kind == dds::RELIABLE_RELIABILITY_QOS);
  CHECK(DataWriterQosFor(Profile::kVideo, c).reliability().kind ==
        dds::BEST_EFFORT_RELIABILITY_QOS);
  CHECK(DataWriterQosFor(Profile::kVideo, c).history().depth == 1);
}

TEST_CASE(
    "QoS profile latched: reliable, keep last 1, transient local, so a late reader gets the last "
    "sample") {
  LinkConfig c;
  namespace dds = eprosima::fastdds::dds;
  for (const auto& qos : {DataWriterQosFor(Profile::kLatched, c).durability().kind,
                          DataReaderQosFor(Profile::kLatched, c).durability().kind}) {
    CHECK(qos == dds::TRANSIENT_LOCAL_DURABILITY_QOS);
  }
  CHECK(DataWriterQosFor(Profile::kLatched, c).reliability().kind == dds::RELIABLE_RELIABILITY_QOS);
  CHECK(DataWriterQosFor(Profile::kLatched, c).history().depth == 1);
}

TEST_CASE("a command crosses between two participants intact") {
  const LinkConfig config = Config(1);
  Participant a(config, "test-a");
  Participant b(config, "test-b");
  std::mutex m;
  msg::TreadCommand got;
  std::atomic<int> count{0};
  TreadCommandReader reader(b, TopicName("t", "command"), Profile::kCommand,
                            [&](const msg::TreadCommand& c) {
                              std::lock_guard lock(m);
                              got = c;
                              ++count;
                            });
  TreadCommandWriter writer(a, TopicName("t", "command"), Profile::kCommand);
  REQUIRE(test::WaitFor([&] { return writer.matched() > 0 && reader.matched() > 0; }, 20.0));
  msg::TreadCommand c;
  c.seq(42);
  c.sent_ns(123456789);
  c.left(0.25F);
  c.right(-0.75F);
  // Best effort: resend until one arrives.
  REQUIRE(test::WaitFor(
      [&] {
        writer.Write(c);
        return count.load() > 0;
      },
      10.0));
  std::lock_guard lock(m);
  CHECK(got.seq() == 42);
  CHECK(got.sent_ns() == 123456789);
  CHECK(got.left() == 0.25F);
  CHECK(got.right() == -0.75F);
}

TEST_CASE(
    "a reader is told each sample's writer: its GUID, which another participant's writer does not "
    "have") {
  const LinkConfig config = Config(9);
  Participant vehicle(config, "test-vehicle");
  Participant owner(config, "test-owner");
  Participant stranger(config, "test-stranger");
  std::mutex m;
  std::vector<WriterId> from;
  TreadCommandReader reader(vehicle, TopicName("t", "command"), Profile::kCommand,
                            [&](const msg::TreadCommand&, const WriterId& writer) {
                              std::lock_guard lock(m);
                              from.push_back(writer);
                            });
  TreadCommandWriter mine(owner, TopicName("t", "command"), Profile::kCommand);
  VideoFeedbackWriter my_feedback(owner, TopicName("t", "video_feedback"), Profile::kState);
  TreadCommandWriter theirs(stranger, TopicName("t", "command"), Profile::kCommand);
  CHECK_FALSE(mine.id().empty());
  CHECK_FALSE(mine.id() == theirs.id());
  // One participant's writers share its GUID prefix; another's do not.
  CHECK(mine.id().SameParticipant(my_feedback.id()));
  CHECK_FALSE(mine.id() == my_feedback.id());
  CHECK_FALSE(mine.id().SameParticipant(theirs.id()));
  msg::TreadCommand c;
  const auto heard = [&](const WriterId& id) {
    std::lock_guard lock(m);
    return std::find(from.begin(), from.end(), id) != from.end();
  };
  REQUIRE(test::WaitFor(
      [&] {
        mine.Write(c);
        theirs.Write(c);
        return heard(mine.id()) && heard(theirs.id());
      },
      20.0));
  std::lock_guard lock(m);
  for (const WriterId& id : from) CHECK((id == mine.id() || id == theirs.id()));
  CHECK(mine.id().ToString().size() == 33);  // 12 bytes, '|', 4 bytes in hex
}

TEST_CASE(
    "a reader may take each sample's stamps: sent when its writer wrote it (the writer's wall "
    "clock), arrived when this side took it (the monotonic clock)") {
  const LinkConfig config = Config(10);
  Participant vehicle(config, "test-vehicle");
  Participant op(config, "test-operator");
  std::mutex m;
  std::vector<std::pair<SampleStamps, uint64_t>> heard;  // the stamps, the sample's seq
  VideoReader reader(op, TopicName("t", "video"), Profile::kVideo,
                     [&](const msg::VideoFrame& f, const SampleStamps& stamps) {
                       std::lock_guard lock(m);
                       heard.emplace_back(stamps, f.seq());
                     });
  VideoWriter writer(vehicle, TopicName("t", "video"), Profile::kVideo);
  msg::VideoFrame f;
  std::vector<std::pair<int64_t, int64_t>> written;  // per seq: wall clock before and after write()
  std::vector<int64_t> written_mono;                 // per seq: monotonic clock before write()
  const auto any = [&] {
    std::lock_guard lock(m);
    return !heard.empty();
  };
  REQUIRE(test::WaitFor(
      [&] {
        f.seq(written.size());
        written_mono.push_back(MonotonicNs());
        const int64_t before = WallNs();
        writer.Write(f);
        written.emplace_back(before, WallNs());
        return any();
      },
      20.0));
  std::lock_guard lock(m);
  const auto& [stamps, seq] = heard.front();
  REQUIRE(seq < written.size());
  CHECK(stamps.writer == writer.id());
  CHECK(stamps.sent_ns >= written[seq].first);
  CHECK(stamps.sent_ns <= written[seq].second);
  CHECK(stamps.arrived_ns >= written_mono[seq]);
  CHECK(stamps.arrived_ns <= MonotonicNs());
}

TEST_CASE(
    "a link beyond the host without DDS Security is said; loopback, --security or --insecure: "
    "not") {
  LinkConfig c;  // the default: loopback only
  CHECK(LinkBeyondHost(c).empty());
  CHECK(InsecureLinkWarning(c, false).empty());
  c.interfaces = {"127.0.0.1", "127.0.1.1"};
  c.discovery_server = "127.0.0.1:11811";
  CHECK(InsecureLinkWarning(c, false).empty());  // a server on this host: still nothing leaves it

  LinkConfig lan = c;
  lan.interfaces = {"127.0.0.1", "192.168.1.20"};
  CHECK(LinkBeyondHost(lan) == "interface 192.168.1.20");
  const std::string warning = InsecureLinkWarning(lan, false);
  CHECK(warning.find(
            "the link reaches beyond this host (interface 192.168.1.20) without DDS Security") ==
        0);
  CHECK(warning.find("guards against mistakes, not attackers") != std::string::npos);
  CHECK(warning.find("--insecure silences this") != std::string::npos);
  CHECK(InsecureLinkWarning(lan, true).empty());
  lan.security = "deployment";
  CHECK(InsecureLinkWarning(lan, false).empty());

  LinkConfig peers;
  peers.peers = {"127.0.0.1", "10.0.0.7"};
  CHECK(LinkBeyondHost(peers) == "peer 10.0.0.7");
  LinkConfig server;
  server.discovery_server = "10.0.0.9:11811";
  CHECK(LinkBeyondHost(server) == "discovery server 10.0.0.9:11811");
  CHECK_FALSE(InsecureLinkWarning(server, false).empty());
}

TEST_CASE("a latched topic: a reader that joins after the last write still gets it, once") {
  const LinkConfig config = Config(7);
  Participant a(config, "test-a");
  Participant b(config, "test-b");
  using SelectedWriter = Writer<msg::SelectedSource, msg::SelectedSourcePubSubType>;
  using SelectedReader = Reader<msg::SelectedSource, msg::SelectedSourcePubSubType>;
  SelectedWriter writer(a, TopicName("robot-a", "selected"), Profile::kLatched);
  msg::SelectedSource first, last;
  first.vehicle("robot-a");
  first.lock("handover");
  last.vehicle("robot-a");
  last.source("operator");
  last.stamp_ns(42);
  REQUIRE(writer.Write(first));
  REQUIRE(writer.Write(last));  // written before anyone reads
  std::mutex m;
  std::vector<msg::SelectedSource> got;
  SelectedReader reader(b, TopicName("robot-a", "selected"), Profile::kLatched,
                        [&](const msg::SelectedSource& s) {
                          std::lock_guard lock(m);
                          got.push_back(s);
                        });
  REQUIRE(test::WaitFor(
      [&] {
        std::lock_guard lock(m);
        return !got.empty();
      },
      20.0));
  std::lock_guard lock(m);
  REQUIRE(got.size() == 1);  // keep last 1: the current one, not the history
  CHECK(std::string(got[0].source().c_str()) == "operator");
  CHECK(std::string(got[0].lock().c_str()).empty());
  CHECK(got[0].stamp_ns() == 42);
}

TEST_CASE("topics of different vehicles do not mix") {
  const LinkConfig config = Config(2);
  Participant a(config, "test-a");
  Participant b(config, "test-b");
  std::atomic<int> count{0};
  StateReader reader(b, TopicName("other", "state"), Profile::kState,
                     [&](const msg::VehicleState&) { ++count; });
  StateReader mine(b, TopicName("mine", "state"), Profile::kState, [](const msg::VehicleState&) {});
  StateWriter writer(a, TopicName("mine", "state"), Profile::kState);
  REQUIRE(test::WaitFor([&] { return mine.matched() > 0 && writer.matched() > 0; }, 20.0));
  msg::VehicleState s;
  REQUIRE(test::WaitFor(
      [&] {
        writer.Write(s);
        return mine.received() >= 20;
      },
      10.0));
  CHECK(count.load() == 0);
  CHECK(reader.matched() == 0);
}

TEST_CASE("a video frame of realistic size arrives byte for byte") {
  const LinkConfig config = Config(3);
  Participant a(config, "test-a");
  Participant b(config, "test-b");
  std::mutex m;
  std::vector<uint8_t> got;
  VideoReader reader(b, TopicName("t", "video"), Profile::kVideo, [&](const msg::VideoFrame& f) {
    std::lock_guard lock(m);
    got = f.data();
  });
  VideoWriter writer(a, TopicName("t", "video"), Profile::kVideo);
  REQUIRE(test::WaitFor([&] { return writer.matched() > 0; }, 20.0));
  msg::VideoFrame f;
  f.encoding("jpeg");
  f.data().resize(90'000);  // larger than one UDP datagram: fragmented
  for (size_t i = 0; i < f.data().size(); ++i) f.data()[i] = static_cast<uint8_t>(i * 31 + 7);
  const std::vector<uint8_t> expected = f.data();
  REQUIRE(test::WaitFor(
      [&] {
        writer.Write(f);
        std::lock_guard lock(m);
        return !got.empty();
      },
      10.0));
  std::lock_guard lock(m);
  CHECK(got == expected);
}

TEST_CASE("a participant refuses a link config LinkConfig::ValidateOrThrow refuses") {
  LinkConfig c = Config(4);
  c.domain_id = 300;
  CHECK_THROWS_WITH(Participant(c, "test-bad"),
                    Catch::Contains("domain_id: expected a whole number in [0, 232]"));
  c = Config(4);
  c.interfaces = {"eth0"};
  CHECK_THROWS_WITH(Participant(c, "test-bad"),
                    Catch::Contains("interfaces[0]: expected an IPv4 address"));
  CHECK_THROWS_AS(Participant(c, "test-bad"), ConfigFieldError);
}
