// The session recorder (record/session_recorder.hpp): what each producer
// hands it lands on its channel with its schema, decodes back, and is
// counted; the servo loop's push allocates nothing; a message too large for
// its ring is dropped and counted, never blocking; a file that cannot be
// made is said, naming it.
#include <fastdds/rtps/common/SerializedPayload.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <string>

#include "alloc_counter.hpp"
#include "haptel/mcap/reader.hpp"
#include "haptel/msg/haptel.h"
#include "haptel/msg/haptelPubSubTypes.h"
#include "haptel/record/session_channels.hpp"
#include "haptel/record/session_recorder.hpp"
#include "haptel/session/foxglove.h"
#include "haptel/session/foxglovePubSubTypes.h"
#include "haptel/session/session.h"
#include "haptel/session/sessionPubSubTypes.h"
#include "test_env.hpp"

namespace fs = std::filesystem;
using namespace haptel;
namespace channels = haptel::record::session;

namespace {

/// A fastddsgen type's CDR bytes, as DDS puts it on the wire.
template <typename PubSub, typename Msg>
std::vector<uint8_t> Cdr(Msg& msg) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&msg)());
  REQUIRE(type.serialize(&msg, &payload));
  return {payload.data, payload.data + payload.length};
}

template <typename PubSub, typename Msg>
void Decode(const mcap::MessageView& m, Msg& out) {
  PubSub type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(m.size));
  std::memcpy(payload.data, m.data, m.size);
  payload.length = static_cast<uint32_t>(m.size);
  REQUIRE(type.deserialize(&payload, &out));
}

}  // namespace

TEST_CASE("a session file holds each producer's messages on its channel, decodable by its schema") {
  const fs::path dir = test::ScratchDir("session-recorder");
  const fs::path file = dir / "sessions" / "lap.mcap";  // the folder is made
  const fs::path attached = dir / "vehicle.yaml";
  { std::ofstream(attached) << "name: robot\n"; }
  record::SessionFileOptions options;
  options.file = file;
  options.run_metadata = {{"command_line", "haptel run --session lap.mcap"}};
  options.study_metadata = {{"participant", "A"}, {"condition", "gesture"}, {"position", "2"}};
  options.attachments = {attached};
  record::SessionRecorder recorder(options);

  // Two DDS channels, as a participant's writer and reader make them.
  const int command = recorder.OnTopic("haptel/robot/command", "haptel::msg::TreadCommand",
                                       link::TapDirection::kSent);
  const int video = recorder.OnTopic("haptel/robot/video", "haptel::msg::VideoFrame",
                                     link::TapDirection::kReceived);
  REQUIRE(command >= 0);
  REQUIRE(video >= 0);
  CHECK(recorder.WantsBytes(command));
  CHECK_FALSE(recorder.WantsBytes(video));  // written as foxglove's video, from the sample
  msg::TreadCommand c;
  std::vector<std::vector<uint8_t>> sent;
  for (int i = 1; i <= 5; ++i) {
    c.seq(i);
    c.left(0.1f * static_cast<float>(i));
    sent.push_back(Cdr<msg::TreadCommandPubSubType>(c));
    recorder.OnSample(command, 1000 + i, &c, sent.back().data(), sent.back().size());
  }
  msg::VideoFrame frame;
  frame.seq(42);
  frame.capture_wall_ns(1'700'000'000'123'456'789);
  frame.encoding("h264");
  frame.data({0, 0, 0, 1, 0x67, 1, 2, 3});
  recorder.OnSample(video, 2000, &frame, nullptr, 0);

  // The servo loop's ticks: pushed without allocating.
  haptics::ServoSample tick;
  tick.wrist_force = {1.0, 2.0, 3.0};
  tick.passivity_energy_j = 0.25;
  const uint64_t before = test::ThreadAllocations();
  for (int i = 0; i < 100; ++i) {
    tick.t_ns = 3000 + i;
    tick.cycle = static_cast<uint64_t>(i);
    tick.side = static_cast<uint8_t>(i % 2);
    recorder.Push(tick);
  }
  CHECK(test::ThreadAllocations() == before);

  recorder.InterfaceEvent(
      record::SessionEvent::Make(4000, 1.5, "switch", 1, 255, 0.0, "gesture -> cockpit"));
  recorder.LapEvent(record::SessionEvent::Make(4001, 2.5, "gate", 0, 255, 12.25, "robot"));
  record::SessionGhost ghost;
  ghost.t_ns = 4002;
  ghost.valid = true;
  ghost.x = 1.5;
  recorder.Ghost(ghost);
  haptics::ForceField field;
  field.guidance_active = true;
  field.guidance_max_force = 6.0;
  recorder.Field(4003, 1, field);

  const record::SessionFileReport report = recorder.Close();
  INFO(report.error);
  REQUIRE(report.saved);
  CHECK(report.dropped == 0);
  CHECK(report.Messages("haptel/robot/command") == 5);
  CHECK(report.Messages("haptel/robot/video") == 1);
  CHECK(report.Messages(std::string(channels::kServoTopic)) == 100);
  CHECK(record::SessionFileJson(report).find("\"saved\":true") != std::string::npos);

  const mcap::Reader reader = mcap::Reader::Open(file);
  CHECK(reader.Verify().empty());
  CHECK(reader.profile() == "haptel");
  std::map<std::string, int> per_topic;
  std::vector<std::vector<uint8_t>> commands;
  reader.ForEachMessage([&](const mcap::MessageView& m) {
    ++per_topic[m.channel->topic];
    const mcap::Schema& schema = reader.schemas().at(m.channel->schema_id);
    CHECK(schema.encoding == "omgidl");
    CHECK(m.channel->message_encoding == "cdr");
    if (m.channel->topic == "haptel/robot/command") {
      CHECK(schema.name == "haptel::msg::TreadCommand");
      CHECK(m.channel->metadata.at("direction") == "sent");
      commands.emplace_back(m.data, m.data + m.size);
    } else if (m.channel->topic == "haptel/robot/video") {
      CHECK(schema.name == channels::kCompressedVideoSchema);
      CHECK(m.sequence == 42);
      CHECK(m.publish_time_ns == 1'700'000'000'123'456'789u);
      foxglove::CompressedVideo v;
      Decode<foxglove::CompressedVideoPubSubType>(m, v);
      CHECK(v.format() == "h264");
      CHECK(v.data() == frame.data());
      CHECK(v.timestamp().sec() == 1'700'000'000u);
      CHECK(v.timestamp().nsec() == 123'456'789u);
    } else if (m.channel->topic == channels::kServoTopic) {
      CHECK(schema.name == channels::kServoTickSchema);
      haptel::session::ServoTick t;
      Decode<haptel::session::ServoTickPubSubType>(m, t);
      CHECK(t.wrist_force()[2] == 3.0f);
      CHECK(t.passivity_energy_j() == 0.25f);
    } else if (m.channel->topic == channels::kLapEventsTopic) {
      haptel::session::Event e;
      Decode<haptel::session::EventPubSubType>(m, e);
      CHECK(e.kind() == "gate");
      CHECK(e.value() == 12.25);
    } else if (m.channel->topic == channels::kFieldTopic) {
      haptel::session::Field f;
      Decode<haptel::session::FieldPubSubType>(m, f);
      CHECK(f.guidance_active());
      CHECK(f.side() == 1);
    }
  });
  CHECK(commands == sent);  // the bytes as they crossed the link
  CHECK(per_topic[std::string(channels::kInterfaceEventsTopic)] == 1);
  CHECK(per_topic[std::string(channels::kGhostTopic)] == 1);
  // Every schema is the IDL text its type is in.
  for (const auto& [id, schema] : reader.schemas()) {
    const std::string& idl = schema.data;
    const std::string type = schema.name.substr(schema.name.rfind("::") + 2);
    CHECK(idl.find("struct " + type) != std::string::npos);
  }
  REQUIRE(reader.summary().metadata_indexes.size() == 2);
  std::map<std::string, std::map<std::string, std::string>> metadata;
  for (const auto& index : reader.summary().metadata_indexes) {
    const mcap::Metadata m = reader.ReadMetadata(index);
    metadata[m.name] = m.metadata;
  }
  CHECK(metadata["haptel"].at("command_line") == "haptel run --session lap.mcap");
  CHECK_FALSE(metadata["haptel"].at("version").empty());
  CHECK(metadata["study"].at("participant") == "A");
  REQUIRE(reader.summary().attachment_indexes.size() == 1);
  const mcap::Attachment a = reader.ReadAttachment(reader.summary().attachment_indexes[0]);
  CHECK(a.name == attached.string());
  CHECK(a.data == "name: robot\n");
}

TEST_CASE("a message larger than its ring is dropped and counted, the rest recorded") {
  const fs::path file = test::ScratchDir("session-recorder-drop") / "drop.mcap";
  record::SessionFileOptions options;
  options.file = file;
  options.video_ring_bytes = 4096;
  record::SessionRecorder recorder(options);
  const int video = recorder.OnTopic("haptel/robot/video", "haptel::msg::VideoFrame",
                                     link::TapDirection::kReceived);
  msg::VideoFrame frame;
  frame.encoding("jpeg");
  frame.data(std::vector<uint8_t>(100, 7));
  recorder.OnSample(video, 1, &frame, nullptr, 0);
  frame.data(std::vector<uint8_t>(8192, 7));  // more than the whole ring
  recorder.OnSample(video, 2, &frame, nullptr, 0);
  const record::SessionFileReport report = recorder.Close();
  REQUIRE(report.saved);
  CHECK(report.dropped == 1);
  CHECK(report.Messages("haptel/robot/video") == 1);
  const std::string json = record::SessionFileJson(report);
  CHECK(json.find("\"schema\":\"foxglove::CompressedImage\"") != std::string::npos);
  CHECK(record::SessionFileLine(report).find("1 dropped") != std::string::npos);
}

TEST_CASE("a session file that cannot be made is said, naming it") {
  const fs::path dir = test::ScratchDir("session-recorder-bad");
  const fs::path blocker = dir / "not-a-folder";
  { std::ofstream(blocker) << "x"; }
  record::SessionFileOptions options;
  options.file = blocker / "lap.mcap";
  try {
    record::SessionRecorder recorder(options);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find(blocker.string()) != std::string::npos);
  }
}

TEST_CASE(
    "each received state's pose and the ghost's are recorded as foxglove::PoseInFrame in the world "
    "frame") {
  const fs::path file = test::ScratchDir("session-recorder-pose") / "pose.mcap";
  record::SessionFileOptions options;
  options.file = file;
  record::SessionRecorder recorder(options);
  const int robot = recorder.OnTopic("haptel/robot1/state", "haptel::msg::VehicleState",
                                     link::TapDirection::kReceived);
  const int blimp = recorder.OnTopic("haptel/blimp1/state", "haptel::msg::BlimpState",
                                     link::TapDirection::kReceived);
  // A vehicle node's own states (sent) are not the run's odometry: no pose.
  const int own = recorder.OnTopic("haptel/robot2/state", "haptel::msg::VehicleState",
                                   link::TapDirection::kSent);
  REQUIRE(robot >= 0);
  REQUIRE(blimp >= 0);
  REQUIRE(own >= 0);
  msg::VehicleState s;
  s.pose_valid(true);
  s.x(1.0f);
  s.y(2.0f);
  s.heading(static_cast<float>(M_PI / 2));
  std::vector<uint8_t> bytes = Cdr<msg::VehicleStatePubSubType>(s);
  recorder.OnSample(robot, 1000, &s, bytes.data(), bytes.size());
  recorder.OnSample(own, 1000, &s, bytes.data(), bytes.size());
  s.pose_valid(false);  // a real robot that knows no pose: none recorded
  bytes = Cdr<msg::VehicleStatePubSubType>(s);
  recorder.OnSample(robot, 1001, &s, bytes.data(), bytes.size());
  msg::BlimpState b;
  b.pose_valid(true);
  b.z(3.0f);
  b.pitch(static_cast<float>(M_PI / 2));  // nose straight up
  bytes = Cdr<msg::BlimpStatePubSubType>(b);
  recorder.OnSample(blimp, 1002, &b, bytes.data(), bytes.size());
  record::SessionGhost ghost;
  ghost.t_ns = 1003;
  ghost.valid = true;
  ghost.x = 4.0;
  ghost.heading = M_PI;
  recorder.Ghost(ghost);
  const record::SessionFileReport report = recorder.Close();
  REQUIRE(report.saved);
  CHECK(report.Messages("haptel/robot1/pose") == 1);
  CHECK(report.Messages("haptel/robot1/state") == 2);
  CHECK(report.Messages("haptel/blimp1/pose") == 1);
  CHECK(report.Messages("haptel/robot2/pose") == 0);
  CHECK(report.Messages(std::string(channels::kGhostPoseTopic)) == 1);

  const mcap::Reader reader = mcap::Reader::Open(file);
  std::map<std::string, foxglove::PoseInFrame> poses;
  reader.ForEachMessage([&](const mcap::MessageView& m) {
    if (reader.schemas().at(m.channel->schema_id).name != channels::kPoseInFrameSchema) return;
    Decode<foxglove::PoseInFramePubSubType>(m, poses[m.channel->topic]);
  });
  REQUIRE(poses.size() == 3);
  const auto& r = poses["haptel/robot1/pose"];
  CHECK(r.frame_id() == channels::kPoseFrame);
  CHECK(r.pose().position().x() == 1.0);
  CHECK(r.pose().position().y() == 2.0);
  // A quarter turn counter-clockwise about z.
  CHECK(r.pose().orientation().z() == Approx(std::sqrt(0.5)));
  CHECK(r.pose().orientation().w() == Approx(std::sqrt(0.5)));
  const auto& up = poses["haptel/blimp1/pose"];
  CHECK(up.pose().position().z() == 3.0);
  // Nose up: a negative quarter turn about the body's y (left) axis.
  CHECK(up.pose().orientation().y() == Approx(-std::sqrt(0.5)));
  CHECK(up.pose().orientation().w() == Approx(std::sqrt(0.5)));
  const auto& g = poses[std::string(channels::kGhostPoseTopic)];
  CHECK(g.pose().position().x() == 4.0);
  CHECK(std::abs(g.pose().orientation().z()) == Approx(1.0));
}
