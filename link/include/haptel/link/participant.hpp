#pragma once
/// @file A DDS participant set up from a LinkConfig, and Haptel's QoS profiles.
///
/// Transports are restricted to the configured interfaces (loopback by default)
/// with unicast discovery through the configured peers, so a default
/// installation sends nothing beyond the host. With LinkConfig::fault the
/// UDP transport is wrapped in the fault transport (fault_transport.hpp)
/// and everything that would bypass it is off: shared memory, data sharing
/// and intra-process delivery.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <string>

#include "haptel/config/link.hpp"
#include "haptel/link/fault_transport.hpp"
#include "haptel/link/sample_tap.hpp"

namespace haptel::link {

/// The three kinds of traffic, each with its own QoS (see DataWriterQosFor).
enum class Profile {
  kCommand,  ///< best effort, keep last 1, deadline = LinkConfig::command_deadline_s
  kState,    ///< reliable, keep last 8
  kVideo,    ///< best effort, keep last 1
  /// Reliable, keep last 1, transient local: a reader that joins late gets
  /// the last sample at once (a state that changes seldom: the fleet's
  /// selected source).
  kLatched,
};

eprosima::fastdds::dds::DataWriterQos DataWriterQosFor(Profile profile, const LinkConfig& config);
eprosima::fastdds::dds::DataReaderQos DataReaderQosFor(Profile profile, const LinkConfig& config);

/// "haptel/<vehicle>/<channel>": several vehicles can share one domain.
std::string TopicName(const std::string& vehicle, const std::string& channel);

/// The SCHED_FIFO priority of the link's own threads (Fast DDS's receive,
/// event and data-sharing threads, the fault transport's delivery), where
/// the process may: they start from a thread raised to it for the moment
/// (RealtimeWhile with StartedThreads::kInherit, core/loop_meter.hpp), as a participant, reader
/// or writer is made. At normal priority on a loaded host they held a
/// command or a state for up to a second: the vehicle's watchdog stopped
/// it mid-drive, and the operator's states came late. Below a vehicle's
/// control loop (57) and the operator's session (60), physics (70) and
/// servo (80) loops, whose ticks are short: these threads also carry video.
inline constexpr int kLinkThreadPriority = 55;

/// Owns a DomainParticipant with one publisher and one subscriber.
/// Writers and readers made on it must be destroyed before it.
class Participant {
 public:
  /// Throws std::runtime_error when DDS refuses to create the participant,
  /// ConfigFieldError for a `config` LinkConfig::ValidateOrThrow refuses.
  /// `listener` (optional; it must outlive the participant) hears the
  /// discovery from the first announcement on (`haptel record` finds the
  /// domain's writers through it).
  Participant(const LinkConfig& config, const std::string& name,
              eprosima::fastdds::dds::DomainParticipantListener* listener = nullptr);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() const { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() const { return subscriber_; }
  const LinkConfig& config() const { return config_; }
  /// The fault transport's line (null without LinkConfig::fault).
  FaultLine* fault_line() const { return line_.get(); }
  /// Taps every writer and reader made on this participant from now on
  /// (null: none): a session file's recorder. It must outlive them.
  void SetTap(SampleTap* tap) { tap_ = tap; }
  SampleTap* tap() const { return tap_; }

 private:
  LinkConfig config_;
  SampleTap* tap_ = nullptr;
  std::shared_ptr<FaultLine> line_;  ///< with LinkConfig::fault: its delay line
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

/// A Fast DDS discovery server (`haptel discovery-server`): participants
/// with LinkConfig::discovery_server = its address meet through it instead
/// of finding each other. Serves while it lives.
class DiscoveryServer {
 public:
  /// Listens on `address`:`port` (UDP). Throws std::runtime_error when DDS
  /// refuses (the port taken, the address not this host's).
  DiscoveryServer(const std::string& address, int port);
  ~DiscoveryServer();
  DiscoveryServer(const DiscoveryServer&) = delete;
  DiscoveryServer& operator=(const DiscoveryServer&) = delete;

 private:
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
};

}  // namespace haptel::link
