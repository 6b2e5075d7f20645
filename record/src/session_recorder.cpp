#include "haptel/record/session_recorder.hpp"

#include <fastdds/rtps/common/SerializedPayload.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "haptel/core/clock.hpp"
#include "haptel/core/json.hpp"
#include "haptel/mcap/writer.hpp"
#include "haptel/msg/haptel.h"
#include "haptel/msg/haptelPubSubTypes.h"
#include "haptel/record/session_channels.hpp"
#include "haptel/session/foxglove.h"
#include "haptel/session/foxglovePubSubTypes.h"
#include "haptel/session/session.h"
#include "haptel/session/sessionPubSubTypes.h"

namespace haptel::record {

namespace {

namespace idl = ::haptel::session;  // the generated types (record::session is the channels' list)

constexpr uint64_t kWrap = ~uint64_t{0};  ///< a byte ring's "continue at the start"

size_t Align8(size_t n) { return (n + 7) & ~size_t{7}; }

/// A single-producer, single-consumer ring of variable-sized messages: each
/// is {u64 record length, Header, payload} padded to 8 bytes, never split
/// (a message that does not fit before the end leaves a wrap mark and goes
/// to the start). Wait-free and allocation-free after construction, like
/// core/spsc_ring.hpp.
class ByteRing {
 public:
  struct Header {
    int64_t mono_ns;
    int64_t publish_wall_ns;  ///< 0: the log time
    uint32_t sequence;
    uint32_t size;
    uint8_t codec;  ///< the video's: 0 JPEG, 1 H.264
    uint8_t reserved[7];
  };

  explicit ByteRing(size_t bytes) {
    size_ = 64;
    while (size_ < bytes) size_ <<= 1;
    buffer_ = std::make_unique<uint8_t[]>(size_);
  }

  /// Producer. False when the ring has no room now (or never will).
  bool Push(const Header& header, const void* data, size_t size) {
    const size_t need = Align8(sizeof(uint64_t) + sizeof(Header) + size);
    if (need > size_ / 2) return false;
    size_t head = head_.load(std::memory_order_relaxed);
    const size_t tail = tail_.load(std::memory_order_acquire);
    const size_t at = head & (size_ - 1);
    const size_t before_end = size_ - at;
    const size_t skip = need > before_end ? before_end : 0;
    if (size_ - (head - tail) < skip + need) return false;
    if (skip != 0) {
      std::memcpy(&buffer_[at], &kWrap, sizeof kWrap);
      head += skip;
    }
    uint8_t* out = &buffer_[head & (size_ - 1)];
    const uint64_t length = need;
    std::memcpy(out, &length, sizeof length);
    std::memcpy(out + sizeof length, &header, sizeof header);
    if (size != 0) std::memcpy(out + sizeof length + sizeof header, data, size);
    head_.store(head + need, std::memory_order_release);
    return true;
  }

  /// Consumer: calls `f(header, payload)` for each message in the ring now.
  template <typename F>
  void Drain(F&& f) {
    size_t tail = tail_.load(std::memory_order_relaxed);
    const size_t head = head_.load(std::memory_order_acquire);
    while (tail != head) {
      const uint8_t* in = &buffer_[tail & (size_ - 1)];
      uint64_t length = 0;
      std::memcpy(&length, in, sizeof length);
      if (length == kWrap) {
        tail += size_ - (tail & (size_ - 1));
        continue;
      }
      Header header;
      std::memcpy(&header, in + sizeof length, sizeof header);
      f(header, in + sizeof length + sizeof header);
      tail += length;
      tail_.store(tail, std::memory_order_release);
    }
    tail_.store(tail, std::memory_order_release);
  }

 private:
  size_t size_ = 0;
  std::unique_ptr<uint8_t[]> buffer_;
  alignas(64) std::atomic<size_t> head_{0};
  alignas(64) std::atomic<size_t> tail_{0};
};

/// A session message's CDR bytes (encapsulation header included), by its
/// fastddsgen type support.
template <typename PubSubType, typename Msg>
void Serialize(Msg& msg, eprosima::fastrtps::rtps::SerializedPayload_t& payload) {
  static PubSubType type;  // stateless but for its name and sizes
  const uint32_t size = type.getSerializedSizeProvider(&msg)();
  if (payload.max_size < size) payload.reserve(size);
  payload.length = 0;
  payload.pos = 0;
  if (!type.serialize(&msg, &payload))
    throw std::runtime_error(std::string("cannot serialize a ") + type.getName());
}

template <size_t N>
std::array<float, N> Floats(const std::array<double, N>& v) {
  std::array<float, N> out{};
  for (size_t i = 0; i < N; ++i) out[i] = static_cast<float>(v[i]);
  return out;
}

void CopyText(char* out, size_t capacity, const char* text) {
  if (text == nullptr) text = "";
  const size_t n = std::min(std::strlen(text), capacity - 1);
  std::memcpy(out, text, n);
  out[n] = '\0';
}

/// A body's orientation from its yaw (about z, counter-clockwise from +x),
/// pitch (nose up positive) and roll (right side down positive), in a frame
/// of x forward, y left, z up: yaw, then pitch, then roll (z-y-x).
foxglove::Quaternion Orientation(double yaw, double pitch = 0.0, double roll = 0.0) {
  // Nose up is a negative turn about the body's y axis (which points left).
  const double cy = std::cos(yaw / 2), sy = std::sin(yaw / 2);
  const double cp = std::cos(-pitch / 2), sp = std::sin(-pitch / 2);
  const double cr = std::cos(roll / 2), sr = std::sin(roll / 2);
  foxglove::Quaternion q;
  q.w(cy * cp * cr + sy * sp * sr);
  q.x(cy * cp * sr - sy * sp * cr);
  q.y(cy * sp * cr + sy * cp * sr);
  q.z(sy * cp * cr - cy * sp * sr);
  return q;
}

foxglove::PoseInFrame PoseIn(int64_t wall_ns, double x, double y, double z,
                             const foxglove::Quaternion& orientation) {
  foxglove::PoseInFrame m;
  m.timestamp().sec(static_cast<uint32_t>(wall_ns / 1000000000));
  m.timestamp().nsec(static_cast<uint32_t>(wall_ns % 1000000000));
  m.frame_id(std::string(session::kPoseFrame));
  m.pose().position().x(x);
  m.pose().position().y(y);
  m.pose().position().z(z);
  m.pose().orientation(orientation);
  return m;
}

/// A sample back from the CDR bytes the tap kept; false when they do not
/// decode (then no pose is derived from it).
template <typename PubSubType, typename Msg>
bool Deserialize(const uint8_t* data, size_t size, Msg& msg) {
  static PubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<uint32_t>(size));
  std::memcpy(payload.data, data, size);
  payload.length = static_cast<uint32_t>(size);
  try {
    return type.deserialize(&payload, &msg);
  } catch (const std::exception&) {
    return false;  // Fast CDR throws on a short buffer
  }
}

/// "2026-11-28T23:38:07Z".
std::string UtcText(int64_t wall_ns) {
  const std::time_t seconds = static_cast<std::time_t>(wall_ns / 1000000000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::string ReadWhole(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in)
    throw std::runtime_error("session file: cannot read '" + file.string() + "' to attach it");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

struct SessionRecorder::ByteChannel {
  ByteChannel(size_t ring_bytes, bool video) : ring(ring_bytes), video(video) {}
  ByteRing ring;
  bool video;  ///< a VideoFrame: written as foxglove's video (its channels made at its first frame)
  uint16_t id = 0;
  std::array<int, 2> video_ids{-1, -1};  ///< JPEG's and H.264's channel (-1: not yet)
  std::string topic, schema;
  std::map<std::string, std::string> metadata;
  SessionChannelCount count;
  std::array<SessionChannelCount, 2> video_counts;
  std::atomic<uint64_t> dropped{0};
  /// A received state's pose, derived from its bytes (kNone: not a state).
  PoseSource pose = PoseSource::kNone;
  uint16_t pose_id = 0;
  SessionChannelCount pose_count;
};

SessionEvent SessionEvent::Make(int64_t t_ns, double t_s, const char* kind, int32_t index,
                                uint8_t side, double value, const char* text) {
  SessionEvent e;
  e.t_ns = t_ns;
  e.t_s = t_s;
  CopyText(e.kind, sizeof e.kind, kind);
  e.index = index;
  e.side = side;
  e.value = value;
  CopyText(e.text, sizeof e.text, text);
  return e;
}

std::string SessionFileJson(const SessionFileReport& r) {
  if (r.file.empty()) return "null";
  std::string out = "{\"file\":" + JsonString(r.file.string()) +
                    ",\"saved\":" + (r.saved ? "true" : "false") +
                    ",\"error\":" + JsonString(r.error) + ",\"bytes\":" + std::to_string(r.bytes) +
                    ",\"dropped\":" + std::to_string(r.dropped) +
                    ",\"thread_cpu_s\":" + JsonNumber(r.thread_cpu_s) +
                    ",\"duration_s\":" + JsonNumber(r.duration_s) + ",\"channels\":[";
  for (size_t i = 0; i < r.channels.size(); ++i) {
    const SessionChannelCount& c = r.channels[i];
    out += (i == 0 ? "" : ",");
    out += "{\"topic\":" + JsonString(c.topic) + ",\"schema\":" + JsonString(c.schema) +
           ",\"messages\":" + std::to_string(c.messages) + ",\"bytes\":" + std::to_string(c.bytes) +
           ",\"dropped\":" + std::to_string(c.dropped) + "}";
  }
  return out + "]}";
}

std::string SessionFileLine(const SessionFileReport& r) {
  if (!r.saved) return "session file " + r.file.string() + " NOT saved: " + r.error;
  uint64_t messages = 0;
  for (const SessionChannelCount& c : r.channels) messages += c.messages;
  char line[96];
  std::snprintf(line, sizeof line, ": %llu messages on %zu channels, %.1f MB, %llu dropped",
                static_cast<unsigned long long>(messages), r.channels.size(),
                static_cast<double>(r.bytes) / 1e6, static_cast<unsigned long long>(r.dropped));
  return "session file " + r.file.string() + line;
}

uint64_t SessionFileReport::Messages(const std::string& topic) const {
  uint64_t n = 0;
  for (const SessionChannelCount& c : channels)
    if (c.topic == topic) n += c.messages;
  return n;
}

SessionRecorder::SessionRecorder(SessionFileOptions options)
    : options_(std::move(options)), events_(1024), ghosts_(4096), fields_(1024) {
  for (auto& ring : servo_rings_)
    ring = std::make_unique<SpscRing<haptics::ServoSample>>(options_.servo_ring_ticks);
  wall_minus_mono_ns_ = WallNs() - MonotonicNs();
  opened_ns_ = MonotonicNs();
  const std::filesystem::path& file = options_.file;
  if (file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) {
      throw std::runtime_error("session file: cannot create the folder '" +
                               file.parent_path().string() + "': " + ec.message());
    }
  }
  mcap::WriterOptions writer_options;
  writer_options.profile = "haptel";
  writer_ = std::make_unique<mcap::Writer>(file, writer_options);
  options_.run_metadata.emplace("version", HAPTEL_VERSION);
  options_.run_metadata.emplace("started_utc", UtcText(WallNs()));
  const uint64_t now = LogTime(MonotonicNs());
  if (!options_.run_metadata.empty())
    writer_->AddMetadata(std::string(session::kRunMetadata), options_.run_metadata);
  if (!options_.study_metadata.empty())
    writer_->AddMetadata(std::string(session::kStudyMetadata), options_.study_metadata);
  for (const std::filesystem::path& attachment : options_.attachments) {
    const std::string data = ReadWhole(attachment);
    const std::string ext = attachment.extension().string();
    writer_->AddAttachment(attachment.string(),
                           ext == ".xml" ? "application/xml" : "application/yaml", now, data.data(),
                           data.size());
  }
  const std::string session_idl(session::SessionIdl());
  servo_.id = McapChannel(std::string(session::kServoTopic), std::string(session::kServoTickSchema),
                          session_idl, {});
  interface_events_.id = McapChannel(std::string(session::kInterfaceEventsTopic),
                                     std::string(session::kEventSchema), session_idl, {});
  lap_events_.id = McapChannel(std::string(session::kLapEventsTopic),
                               std::string(session::kEventSchema), session_idl, {});
  ghost_.id = McapChannel(std::string(session::kGhostTopic), std::string(session::kGhostSchema),
                          session_idl, {});
  field_.id = McapChannel(std::string(session::kFieldTopic), std::string(session::kFieldSchema),
                          session_idl, {});
  ghost_pose_.id =
      McapChannel(std::string(session::kGhostPoseTopic), std::string(session::kPoseInFrameSchema),
                  std::string(session::FoxgloveIdl()), {});
  servo_.count = {std::string(session::kServoTopic), std::string(session::kServoTickSchema)};
  interface_events_.count = {std::string(session::kInterfaceEventsTopic),
                             std::string(session::kEventSchema)};
  lap_events_.count = {std::string(session::kLapEventsTopic), std::string(session::kEventSchema)};
  ghost_.count = {std::string(session::kGhostTopic), std::string(session::kGhostSchema)};
  field_.count = {std::string(session::kFieldTopic), std::string(session::kFieldSchema)};
  ghost_pose_.count = {std::string(session::kGhostPoseTopic),
                       std::string(session::kPoseInFrameSchema)};
  thread_ = std::thread([this] { Run(); });
}

SessionRecorder::~SessionRecorder() { Close(); }

uint64_t SessionRecorder::LogTime(int64_t mono_ns) const {
  const int64_t wall = mono_ns + wall_minus_mono_ns_;
  return wall > 0 ? static_cast<uint64_t>(wall) : 0;
}

uint16_t SessionRecorder::McapChannel(const std::string& topic, const std::string& schema,
                                      const std::string& idl,
                                      std::map<std::string, std::string> metadata) {
  auto it = schemas_.find(schema);
  if (it == schemas_.end())
    it =
        schemas_
            .emplace(schema, writer_->AddSchema(schema, std::string(session::kSchemaEncoding), idl))
            .first;
  return writer_->AddChannel(it->second, topic, std::string(session::kMessageEncoding),
                             std::move(metadata));
}

int SessionRecorder::OnTopic(const std::string& topic, const std::string& type_name,
                             link::TapDirection direction) {
  const bool video = type_name == "haptel::msg::VideoFrame";
  const bool sent = direction == link::TapDirection::kSent;
  if (video && sent) return -1;  // an operator sends none
  PoseSource pose = PoseSource::kNone;
  if (!sent && type_name == "haptel::msg::VehicleState") pose = PoseSource::kRobot;
  if (!sent && type_name == "haptel::msg::BlimpState") pose = PoseSource::kBlimp;
  return AddByteChannel(topic, type_name, std::string(session::HaptelIdl()),
                        {{"direction", sent ? "sent" : "received"}, {"dds_type", type_name}}, video,
                        pose);
}

int SessionRecorder::AddOwnChannel(const std::string& topic, const std::string& schema,
                                   const std::string& idl) {
  return AddByteChannel(topic, schema, idl, {}, false, PoseSource::kNone);
}

int SessionRecorder::AddByteChannel(const std::string& topic, const std::string& schema,
                                    const std::string& idl,
                                    std::map<std::string, std::string> metadata, bool video,
                                    PoseSource pose) {
  std::lock_guard<std::mutex> lock(writer_mutex_);
  const int index = byte_channel_count_.load();
  if (index >= kMaxByteChannels || closed_) return -1;
  auto channel = std::make_unique<ByteChannel>(
      video ? options_.video_ring_bytes : options_.channel_ring_bytes, video);
  channel->topic = topic;
  channel->schema = schema;
  channel->metadata = std::move(metadata);
  if (!video) {  // the video's channels are made at its first frame, by its codec
    try {
      channel->id = McapChannel(topic, schema, idl, channel->metadata);
      if (pose != PoseSource::kNone) {
        // "haptel/<vehicle>/state" -> "haptel/<vehicle>/pose"
        const std::string pose_topic = topic.substr(0, topic.rfind('/') + 1) + "pose";
        channel->pose_id = McapChannel(pose_topic, std::string(session::kPoseInFrameSchema),
                                       std::string(session::FoxgloveIdl()), {{"from", topic}});
        channel->pose_count = {pose_topic, std::string(session::kPoseInFrameSchema)};
        channel->pose = pose;
      }
    } catch (const std::exception& e) {
      Fail(e.what());
      return -1;
    }
    channel->count = {topic, schema};
  }
  byte_channels_[index] = std::move(channel);
  byte_channel_count_.store(index + 1, std::memory_order_release);
  return index;
}

bool SessionRecorder::WantsBytes(int channel) const {
  return channel >= 0 && channel < kMaxByteChannels && byte_channels_[channel] &&
         !byte_channels_[channel]->video;
}

void SessionRecorder::OnSample(int channel, int64_t now_ns, const void* sample, const uint8_t* cdr,
                               size_t size) {
  ByteChannel& c = *byte_channels_[channel];
  ByteRing::Header header{};
  header.mono_ns = now_ns;
  if (c.video) {
    const auto& frame = *static_cast<const msg::VideoFrame*>(sample);
    header.publish_wall_ns = frame.capture_wall_ns();
    header.sequence = static_cast<uint32_t>(frame.seq());
    header.codec = frame.encoding() == "h264" ? 1 : 0;
    header.size = static_cast<uint32_t>(frame.data().size());
    if (!c.ring.Push(header, frame.data().data(), frame.data().size()))
      c.dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  header.size = static_cast<uint32_t>(size);
  if (!c.ring.Push(header, cdr, size)) c.dropped.fetch_add(1, std::memory_order_relaxed);
}

void SessionRecorder::Push(const haptics::ServoSample& sample) noexcept {
  if (!servo_rings_[sample.side & 1]->Push(sample))
    servo_.dropped.fetch_add(1, std::memory_order_relaxed);
}

void SessionRecorder::InterfaceEvent(const SessionEvent& event) {
  if (!events_.Push({false, event})) interface_events_.dropped.fetch_add(1);
}

void SessionRecorder::LapEvent(const SessionEvent& event) {
  if (!events_.Push({true, event})) lap_events_.dropped.fetch_add(1);
}

void SessionRecorder::Ghost(const SessionGhost& ghost) {
  if (!ghosts_.Push(ghost)) ghost_.dropped.fetch_add(1);
}

void SessionRecorder::Field(int64_t t_ns, uint8_t side, const haptics::ForceField& field) {
  if (!fields_.Push({t_ns, side, field})) field_.dropped.fetch_add(1);
}

void SessionRecorder::Fail(const std::string& what) {
  if (error_.empty()) error_ = what;
}

void SessionRecorder::Run() {
  int64_t last_flush_ns = MonotonicNs();
  const auto flush_ns = static_cast<int64_t>(options_.flush_period_s * 1e9);
  while (!stop_.load(std::memory_order_acquire)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    std::lock_guard<std::mutex> lock(writer_mutex_);
    Drain();
    if (error_.empty() && MonotonicNs() - last_flush_ns >= flush_ns) {
      try {
        writer_->Flush();
      } catch (const std::exception& e) {
        Fail(e.what());
      }
      last_flush_ns = MonotonicNs();
    }
  }
  thread_cpu_s_.store(ThreadCpuSeconds());
}

void SessionRecorder::Drain() {
  const int n = byte_channel_count_.load(std::memory_order_acquire);
  for (int i = 0; i < n; ++i) DrainBytes(*byte_channels_[i]);
  DrainSessionRings();
}

void SessionRecorder::WriteMessage(uint16_t channel, uint32_t sequence, int64_t mono_ns,
                                   int64_t publish_wall_ns, const uint8_t* data, size_t size,
                                   SessionChannelCount& count) {
  if (!error_.empty()) return;  // a failed file takes no more: the report says so
  const uint64_t log_time = LogTime(mono_ns);
  const uint64_t publish_time =
      publish_wall_ns > 0 ? static_cast<uint64_t>(publish_wall_ns) : log_time;
  try {
    writer_->Write(channel, sequence, log_time, publish_time, data, size);
    ++count.messages;
    count.bytes += size;
  } catch (const std::exception& e) {
    Fail(e.what());
  }
}

void SessionRecorder::DrainBytes(ByteChannel& c) {
  eprosima::fastrtps::rtps::SerializedPayload_t payload;
  c.ring.Drain([&](const ByteRing::Header& h, const uint8_t* data) {
    if (!c.video) {
      WriteMessage(c.id, static_cast<uint32_t>(c.count.messages), h.mono_ns, 0, data, h.size,
                   c.count);
      if (c.pose != PoseSource::kNone) WritePose(c, h.mono_ns, data, h.size);
      return;
    }
    const int codec = h.codec;
    if (c.video_ids[codec] < 0) {
      const bool h264 = codec == 1;
      try {
        std::map<std::string, std::string> metadata = c.metadata;
        metadata["format"] = h264 ? "h264" : "jpeg";
        const std::string schema(h264 ? session::kCompressedVideoSchema
                                      : session::kCompressedImageSchema);
        c.video_ids[codec] =
            McapChannel(c.topic, schema, std::string(session::FoxgloveIdl()), metadata);
        c.video_counts[codec] = {c.topic, schema};
      } catch (const std::exception& e) {
        Fail(e.what());
        return;
      }
    }
    foxglove::Time stamp;
    stamp.sec(static_cast<uint32_t>(h.publish_wall_ns / 1000000000));
    stamp.nsec(static_cast<uint32_t>(h.publish_wall_ns % 1000000000));
    const auto write = [&](auto& message, auto type_tag) {
      using PubSub = decltype(type_tag);
      message.timestamp(stamp);
      message.frame_id("camera");
      message.data(std::vector<uint8_t>(data, data + h.size));
      message.format(codec == 1 ? "h264" : "jpeg");
      try {
        Serialize<PubSub>(message, payload);
      } catch (const std::exception& e) {
        Fail(e.what());
        return;
      }
      WriteMessage(static_cast<uint16_t>(c.video_ids[codec]), h.sequence, h.mono_ns,
                   h.publish_wall_ns, payload.data, payload.length, c.video_counts[codec]);
    };
    if (codec == 1) {
      foxglove::CompressedVideo m;
      write(m, foxglove::CompressedVideoPubSubType{});
    } else {
      foxglove::CompressedImage m;
      write(m, foxglove::CompressedImagePubSubType{});
    }
  });
}

void SessionRecorder::WritePose(ByteChannel& c, int64_t mono_ns, const uint8_t* data, size_t size) {
  std::optional<foxglove::PoseInFrame> pose;
  const auto wall_ns = static_cast<int64_t>(LogTime(mono_ns));
  if (c.pose == PoseSource::kRobot) {
    msg::VehicleState state;
    if (Deserialize<msg::VehicleStatePubSubType>(data, size, state) && state.pose_valid())
      pose = PoseIn(wall_ns, state.x(), state.y(), 0.0, Orientation(state.heading()));
  } else {
    msg::BlimpState state;
    if (Deserialize<msg::BlimpStatePubSubType>(data, size, state) && state.pose_valid()) {
      pose = PoseIn(wall_ns, state.x(), state.y(), state.z(),
                    Orientation(state.yaw(), state.pitch(), state.roll()));
    }
  }
  if (!pose) return;
  eprosima::fastrtps::rtps::SerializedPayload_t payload;
  try {
    Serialize<foxglove::PoseInFramePubSubType>(*pose, payload);
  } catch (const std::exception& e) {
    Fail(e.what());
    return;
  }
  WriteMessage(c.pose_id, static_cast<uint32_t>(c.pose_count.messages), mono_ns, 0, payload.data,
               payload.length, c.pose_count);
}

void SessionRecorder::DrainSessionRings() {
  eprosima::fastrtps::rtps::SerializedPayload_t payload;
  const auto write = [&](auto type_tag, auto& message, SideChannel& channel, int64_t t_ns) {
    using PubSub = decltype(type_tag);
    try {
      Serialize<PubSub>(message, payload);
    } catch (const std::exception& e) {
      Fail(e.what());
      return;
    }
    WriteMessage(channel.id, static_cast<uint32_t>(channel.count.messages), t_ns, 0, payload.data,
                 payload.length, channel.count);
  };
  for (auto& ring : servo_rings_) {
    haptics::ServoSample s;
    while (ring->Pop(s)) {
      idl::ServoTick m;
      m.t_ns(s.t_ns);
      m.cycle(s.cycle);
      m.side(s.side);
      m.period_s(static_cast<float>(s.period_s));
      m.tracked_position(Floats(s.tracked_position));
      m.tracked_orientation(Floats(s.tracked_orientation));
      m.coupling(s.coupling);
      m.proxy_position(Floats(s.proxy_position));
      m.field_force(Floats(s.field_force));
      m.wrist_force(Floats(s.wrist_force));
      m.finger_forces(Floats(s.finger_forces));
      m.passivity_energy_j(static_cast<float>(s.passivity_energy_j));
      m.passivity_dissipated_j(static_cast<float>(s.passivity_dissipated_j));
      write(idl::ServoTickPubSubType{}, m, servo_, s.t_ns);
    }
  }
  EventRecord r;
  while (events_.Pop(r)) {
    const SessionEvent& e = r.event;
    idl::Event m;
    m.t_ns(e.t_ns);
    m.t_s(e.t_s);
    m.kind(e.kind);
    m.index(e.index);
    m.side(e.side);
    m.value(e.value);
    m.text(e.text);
    write(idl::EventPubSubType{}, m, r.lap ? lap_events_ : interface_events_, e.t_ns);
  }
  SessionGhost g;
  while (ghosts_.Pop(g)) {
    idl::Ghost m;
    m.t_ns(g.t_ns);
    m.valid(g.valid);
    m.x(g.x);
    m.y(g.y);
    m.z(g.z);
    m.heading(g.heading);
    m.reported_x(g.reported_x);
    m.reported_y(g.reported_y);
    m.reported_z(g.reported_z);
    m.delay_s(g.delay_s);
    write(idl::GhostPubSubType{}, m, ghost_, g.t_ns);
    if (g.valid) {
      foxglove::PoseInFrame pose =
          PoseIn(static_cast<int64_t>(LogTime(g.t_ns)), g.x, g.y, g.z, Orientation(g.heading));
      write(foxglove::PoseInFramePubSubType{}, pose, ghost_pose_, g.t_ns);
    }
  }
  FieldRecord f;
  while (fields_.Pop(f)) {
    const haptics::ForceField& ff = f.field;
    idl::Field m;
    m.t_ns(f.t_ns);
    m.side(f.side);
    m.enabled(ff.enabled);
    m.neutral(ff.neutral);
    m.stiffness(ff.stiffness);
    m.wall_active(ff.wall_active);
    m.wall_point(ff.wall_point);
    m.wall_normal(ff.wall_normal);
    m.guidance_active(ff.guidance_active);
    m.guidance_point(ff.guidance_point);
    m.guidance_normal(ff.guidance_normal);
    m.guidance_max_force(ff.guidance_max_force);
    write(idl::FieldPubSubType{}, m, field_, f.t_ns);
  }
}

SessionFileReport SessionRecorder::Close() {
  if (closed_) return report_;
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  std::lock_guard<std::mutex> lock(writer_mutex_);
  closed_ = true;
  Drain();
  SessionFileReport& r = report_;
  r.file = options_.file;
  try {
    writer_->Close();
  } catch (const std::exception& e) {
    Fail(e.what());
  }
  const auto add = [&r](SessionChannelCount count, uint64_t dropped) {
    count.dropped = dropped;
    r.dropped += dropped;
    r.channels.push_back(std::move(count));
  };
  const int n = byte_channel_count_.load();
  for (int i = 0; i < n; ++i) {
    ByteChannel& c = *byte_channels_[i];
    if (!c.video) {
      add(c.count, c.dropped.load());
      if (c.pose != PoseSource::kNone) add(c.pose_count, 0);
      continue;
    }
    bool any = false;
    for (int codec = 0; codec < 2; ++codec) {
      if (c.video_ids[codec] < 0) continue;
      add(c.video_counts[codec], any ? 0 : c.dropped.load());
      any = true;
    }
    if (!any) add({c.topic, std::string(session::kCompressedVideoSchema)}, c.dropped.load());
  }
  for (SideChannel* side :
       {&servo_, &interface_events_, &lap_events_, &ghost_, &field_, &ghost_pose_})
    add(side->count, side->dropped.load());
  std::error_code ec;
  const auto size = std::filesystem::file_size(options_.file, ec);
  r.bytes = ec ? 0 : size;
  r.error = error_;
  r.saved = error_.empty();
  r.thread_cpu_s = thread_cpu_s_.load();
  r.duration_s = NsToS(MonotonicNs() - opened_ns_);
  return r;
}

}  // namespace haptel::record
