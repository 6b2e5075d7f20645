#pragma once
/// @file Typed DDS writers and readers over a Participant.
///
/// Reader callbacks run on a DDS thread: keep them short (copy into a
/// seqlock or queue) and never call them from a real-time loop. A callback
/// may take the sample's writer (WriterId, from DDS's SampleInfo) beside
/// the sample: who sent it, as no field of the sample can say; or its
/// SampleStamps: when it was written and when it arrived.
#include <atomic>
#include <fastdds/dds/core/status/DeadlineMissedStatus.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <functional>
#include <stdexcept>
#include <string>

#include "haptel/core/clock.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/writer_id.hpp"
#include "haptel/msg/haptel.h"
#include "haptel/msg/haptelPubSubTypes.h"

namespace haptel::link {

namespace detail {
/// Registers the type (once per participant) and creates the topic.
template <typename PubSubType>
eprosima::fastdds::dds::Topic* MakeTopic(Participant& p, const std::string& name) {
  namespace dds = eprosima::fastdds::dds;
  dds::TypeSupport type(new PubSubType());
  type.register_type(p.get());
  dds::Topic* topic = p.get()->create_topic(name, type.get_type_name(), dds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) throw std::runtime_error("link: cannot create topic '" + name + "'");
  return topic;
}

}  // namespace detail

/// A writer's or reader's end of its participant's SampleTap (or of a link
/// on no DDS: a vehicle stepped in this process): the channel it was given
/// and the type support that serializes its samples into a buffer kept from
/// one sample to the next.
template <typename Msg, typename PubSubType>
class Tapped {
 public:
  Tapped(Participant& participant, const std::string& topic, TapDirection direction)
      : Tapped(participant.tap(), topic, direction) {}
  /// On `tap` (null: nothing is tapped).
  Tapped(SampleTap* tap, const std::string& topic, TapDirection direction) : tap_(tap) {
    if (tap_ == nullptr) return;
    channel_ = tap_->OnTopic(topic, type_.getName(), direction);
    bytes_ = channel_ >= 0 && tap_->WantsBytes(channel_);
  }
  /// Hands `msg` to the tap (nothing without one). Its caller's thread.
  void operator()(const Msg& msg, int64_t now_ns) {
    if (channel_ < 0) return;
    if (!bytes_) {
      tap_->OnSample(channel_, now_ns, &msg, nullptr, 0);
      return;
    }
    Msg* data = const_cast<Msg*>(&msg);  // type support's API; it only reads
    const uint32_t size = type_.getSerializedSizeProvider(data)();
    if (payload_.max_size < size) payload_.reserve(size);
    payload_.length = 0;
    payload_.pos = 0;
    if (!type_.serialize(data, &payload_)) return;
    tap_->OnSample(channel_, now_ns, &msg, payload_.data, payload_.length);
  }

 private:
  SampleTap* tap_;
  int channel_ = -1;
  bool bytes_ = false;
  PubSubType type_;
  eprosima::fastrtps::rtps::SerializedPayload_t payload_;
};

/// The WriterId of a DDS GUID.
inline WriterId ToWriterId(const eprosima::fastrtps::rtps::GUID_t& guid) {
  WriterId id;
  std::copy(guid.guidPrefix.value, guid.guidPrefix.value + WriterId::kPrefixSize, id.guid.begin());
  std::copy(guid.entityId.value, guid.entityId.value + 4, id.guid.begin() + WriterId::kPrefixSize);
  return id;
}

/// When a sample left its writer and when it reached this reader, for a
/// delay-based rate estimate (video/rate_estimator.hpp): `sent_ns` is the
/// DDS source timestamp, the writer host's wall clock when write() was
/// called (after the sample was made: a video frame's encoding is not in
/// it); `arrived_ns` this host's monotonic clock in the reader's DDS
/// callback, on the transport's receive thread, before anything is done
/// with the sample. The two clocks differ: only differences of each mean
/// anything.
struct SampleStamps {
  WriterId writer;
  int64_t sent_ns = 0;
  int64_t arrived_ns = 0;
};

template <typename Msg, typename PubSubType>
class Writer : private eprosima::fastdds::dds::DataWriterListener {
 public:
  Writer(Participant& participant, const std::string& topic, Profile profile)
      : participant_(participant), tapped_(participant, topic, TapDirection::kSent) {
    topic_ = detail::MakeTopic<PubSubType>(participant, topic);
    const RealtimeWhile realtime(kLinkThreadPriority,
                                 StartedThreads::kInherit);  // its threads, if any
    writer_ = participant.publisher()->create_datawriter(
        topic_, DataWriterQosFor(profile, participant.config()), this);
    if (writer_ == nullptr)
      throw std::runtime_error("link: cannot create writer on '" + topic + "'");
  }
  ~Writer() override {
    participant_.publisher()->delete_datawriter(writer_);
    participant_.get()->delete_topic(topic_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Sends one sample; false if DDS refused it (counted in failed_writes()).
  bool Write(Msg& msg) {
    const bool ok = writer_->write(&msg);
    if (!ok) failed_writes_.fetch_add(1, std::memory_order_relaxed);
    if (ok) tapped_(msg, MonotonicNs());
    return ok;
  }
  int matched() const { return matched_.load(); }
  /// This writer's GUID, as readers are told it with each of its samples.
  WriterId id() const { return ToWriterId(writer_->guid()); }
  uint64_t failed_writes() const { return failed_writes_.load(); }
  uint64_t deadlines_missed() const { return deadlines_missed_.load(); }

 private:
  void on_publication_matched(eprosima::fastdds::dds::DataWriter*,
                              const eprosima::fastdds::dds::PublicationMatchedStatus& s) override {
    matched_.store(s.current_count);
  }
  void on_offered_deadline_missed(
      eprosima::fastdds::dds::DataWriter*,
      const eprosima::fastdds::dds::OfferedDeadlineMissedStatus&) override {
    deadlines_missed_.fetch_add(1);
  }

  Participant& participant_;
  Tapped<Msg, PubSubType> tapped_;
  eprosima::fastdds::dds::Topic* topic_ = nullptr;
  eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
  std::atomic<int> matched_{0};
  std::atomic<uint64_t> failed_writes_{0};
  std::atomic<uint64_t> deadlines_missed_{0};
};

template <typename Msg, typename PubSubType>
class Reader : private eprosima::fastdds::dds::DataReaderListener {
 public:
  using Callback = std::function<void(const Msg&)>;
  /// The sample and its writer.
  using OriginCallback = std::function<void(const Msg&, const WriterId&)>;
  /// The sample, its writer and its stamps.
  using StampedCallback = std::function<void(const Msg&, const SampleStamps&)>;

  Reader(Participant& participant, const std::string& topic, Profile profile, Callback on_sample)
      : Reader(participant, topic, profile,
               StampedCallback(
                   [f = std::move(on_sample)](const Msg& m, const SampleStamps&) { f(m); })) {}
  Reader(Participant& participant, const std::string& topic, Profile profile,
         OriginCallback on_sample)
      : Reader(participant, topic, profile,
               StampedCallback([f = std::move(on_sample)](const Msg& m, const SampleStamps& s) {
                 f(m, s.writer);
               })) {}
  Reader(Participant& participant, const std::string& topic, Profile profile,
         StampedCallback on_sample)
      : participant_(participant),
        on_sample_(std::move(on_sample)),
        tapped_(participant, topic, TapDirection::kReceived) {
    topic_ = detail::MakeTopic<PubSubType>(participant, topic);
    const RealtimeWhile realtime(kLinkThreadPriority,
                                 StartedThreads::kInherit);  // its data-sharing thread
    reader_ = participant.subscriber()->create_datareader(
        topic_, DataReaderQosFor(profile, participant.config()), this);
    if (reader_ == nullptr)
      throw std::runtime_error("link: cannot create reader on '" + topic + "'");
  }
  ~Reader() override {
    // Detach the listener first so no callback runs into a half-destroyed object.
    reader_->set_listener(nullptr);
    participant_.subscriber()->delete_datareader(reader_);
    participant_.get()->delete_topic(topic_);
  }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  int matched() const { return matched_.load(); }
  uint64_t received() const { return received_.load(); }
  uint64_t deadlines_missed() const { return deadlines_missed_.load(); }

 private:
  void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
    eprosima::fastdds::dds::SampleInfo info;
    while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      received_.fetch_add(1, std::memory_order_relaxed);
      SampleStamps stamps;
      stamps.writer = ToWriterId(info.sample_identity.writer_guid());
      stamps.sent_ns = info.source_timestamp.to_ns();
      stamps.arrived_ns = MonotonicNs();
      tapped_(sample_, stamps.arrived_ns);
      on_sample_(sample_, stamps);
    }
  }
  void on_subscription_matched(
      eprosima::fastdds::dds::DataReader*,
      const eprosima::fastdds::dds::SubscriptionMatchedStatus& s) override {
    matched_.store(s.current_count);
  }
  void on_requested_deadline_missed(
      eprosima::fastdds::dds::DataReader*,
      const eprosima::fastdds::dds::RequestedDeadlineMissedStatus&) override {
    deadlines_missed_.fetch_add(1);
  }

  Participant& participant_;
  StampedCallback on_sample_;
  Tapped<Msg, PubSubType> tapped_;
  Msg sample_;  ///< reused for every take: no allocation per sample for fixed-size types
  eprosima::fastdds::dds::Topic* topic_ = nullptr;
  eprosima::fastdds::dds::DataReader* reader_ = nullptr;
  std::atomic<int> matched_{0};
  std::atomic<uint64_t> received_{0};
  std::atomic<uint64_t> deadlines_missed_{0};
};

using TreadCommandWriter = Writer<msg::TreadCommand, msg::TreadCommandPubSubType>;
using TreadCommandReader = Reader<msg::TreadCommand, msg::TreadCommandPubSubType>;
using StateWriter = Writer<msg::VehicleState, msg::VehicleStatePubSubType>;
using StateReader = Reader<msg::VehicleState, msg::VehicleStatePubSubType>;
using VideoWriter = Writer<msg::VideoFrame, msg::VideoFramePubSubType>;
using VideoReader = Reader<msg::VideoFrame, msg::VideoFramePubSubType>;
using VideoFeedbackWriter = Writer<msg::VideoFeedback, msg::VideoFeedbackPubSubType>;
using VideoFeedbackReader = Reader<msg::VideoFeedback, msg::VideoFeedbackPubSubType>;
// The CAN robot's bus log, on haptel/<vehicle>/can_log (kLatched).
using CanLogWriter = Writer<msg::CanLogStatus, msg::CanLogStatusPubSubType>;
using CanLogReader = Reader<msg::CanLogStatus, msg::CanLogStatusPubSubType>;
// The blimp's, on the same topic names (haptel/<vehicle>/command, .../state).
using BlimpCommandWriter = Writer<msg::BlimpCommand, msg::BlimpCommandPubSubType>;
using BlimpCommandReader = Reader<msg::BlimpCommand, msg::BlimpCommandPubSubType>;
using BlimpStateWriter = Writer<msg::BlimpState, msg::BlimpStatePubSubType>;
using BlimpStateReader = Reader<msg::BlimpState, msg::BlimpStatePubSubType>;

// A steerable camera's command and the vehicle's cameras (families.hpp:
// CameraCommandTopic, CameraStatusTopic).
using CameraCommandWriter = Writer<msg::CameraCommand, msg::CameraCommandPubSubType>;
using CameraCommandReader = Reader<msg::CameraCommand, msg::CameraCommandPubSubType>;
using CameraStatusWriter = Writer<msg::CameraStatus, msg::CameraStatusPubSubType>;
using CameraStatusReader = Reader<msg::CameraStatus, msg::CameraStatusPubSubType>;

}  // namespace haptel::link
