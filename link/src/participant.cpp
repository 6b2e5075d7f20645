#include "haptel/link/participant.hpp"

#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>

#include <cmath>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/log/StdoutErrConsumer.hpp>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/link/security.hpp"

namespace haptel::link {

namespace dds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;

namespace {
/// The server's GUID prefix: Fast DDS's own default for server 0 (what
/// `fastdds discovery -i 0` uses), so either server serves either client.
constexpr const char* kServerPrefix = "44.53.00.5f.45.50.52.4f.53.49.4d.41";

Locator_t UdpLocator(const std::string& address, int port) {
  Locator_t locator;
  locator.kind = LOCATOR_KIND_UDPv4;
  IPLocator::setIPv4(locator, address);
  locator.port = static_cast<uint32_t>(port);
  return locator;
}

/// Fast DDS's own warnings and errors (a security refusal, a port taken) on
/// stderr, where the programs' messages go: stdout carries results (the
/// --json line).
void LogToStderr() {
  static std::once_flag once;
  std::call_once(once, [] {
    dds::Log::ClearConsumers();
    dds::Log::RegisterConsumer(std::make_unique<dds::StdoutErrConsumer>());
  });
}

eprosima::fastrtps::Duration_t ToDuration(double seconds) {
  const auto whole = static_cast<int32_t>(std::floor(seconds));
  const auto ns = static_cast<uint32_t>(std::llround((seconds - whole) * 1e9));
  return eprosima::fastrtps::Duration_t(whole, ns);
}
}  // namespace

std::string TopicName(const std::string& vehicle, const std::string& channel) {
  return "haptel/" + vehicle + "/" + channel;
}

namespace {
/// Writer and reader QoS share these policies; both ends must agree.
template <typename Qos>
Qos WithProfile(Qos qos, Profile profile, const LinkConfig& config) {
  qos.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  switch (profile) {
    case Profile::kCommand:
      qos.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
      qos.history().depth = 1;
      qos.deadline().period = ToDuration(config.command_deadline_s);
      break;
    case Profile::kState:
      qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
      qos.history().depth = 8;
      break;
    case Profile::kVideo:
      qos.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
      qos.history().depth = 1;
      break;
    case Profile::kLatched:
      qos.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
      qos.history().depth = 1;
      qos.durability().kind = dds::TRANSIENT_LOCAL_DURABILITY_QOS;
      break;
  }
  // Data sharing hands samples over in shared memory, past any transport:
  // off when the transport is to inject faults.
  if (config.fault.enabled) qos.data_sharing().off();
  return qos;
}
}  // namespace

dds::DataWriterQos DataWriterQosFor(Profile profile, const LinkConfig& config) {
  return WithProfile(dds::DataWriterQos(dds::DATAWRITER_QOS_DEFAULT), profile, config);
}

dds::DataReaderQos DataReaderQosFor(Profile profile, const LinkConfig& config) {
  return WithProfile(dds::DataReaderQos(dds::DATAREADER_QOS_DEFAULT), profile, config);
}

Participant::Participant(const LinkConfig& config, const std::string& name,
                         eprosima::fastdds::dds::DomainParticipantListener* listener)
    : config_(Validated(config)) {
  // Every thread the participant starts (below) inherits the link's priority.
  const RealtimeWhile realtime(kLinkThreadPriority, StartedThreads::kInherit);
  LogToStderr();
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name(name);
  // Own transports instead of the built-in ones: UDP only on the allowed
  // interfaces, and shared memory between processes of one host.
  qos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList = config.interfaces;
  // Room for many participants per host (tests run several at once).
  udp->maxInitialPeersRange = 32;
  if (config.fault.enabled) {
    // Every packet through the fault transport: no shared memory beside it,
    // and no intra-process shortcut (a process-wide setting).
    line_ = std::make_shared<FaultLine>(config.fault, std::random_device{}());
    qos.transport().user_transports.push_back(MakeFaultTransport(udp, line_));
    eprosima::fastrtps::LibrarySettingsAttributes library;
    library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
    eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);
  } else {
    qos.transport().user_transports.push_back(udp);
    qos.transport().user_transports.push_back(
        std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>());
  }

  // Unicast discovery only: a metatraffic unicast locator on the first allowed
  // interface (port 0: derived from the participant id) disables multicast.
  auto& builtin = qos.wire_protocol().builtin;
  for (const std::string& address : config.interfaces) {
    Locator_t meta;
    meta.kind = LOCATOR_KIND_UDPv4;
    IPLocator::setIPv4(meta, address);
    builtin.metatrafficUnicastLocatorList.push_back(meta);
  }
  for (const std::string& peer : config.peers) {
    Locator_t locator;
    locator.kind = LOCATOR_KIND_UDPv4;
    if (!IPLocator::setIPv4(locator, peer)) {
      throw std::runtime_error("link: peer '" + peer + "' is not an IPv4 address");
    }
    builtin.initialPeersList.push_back(locator);
  }
  if (!config.security.empty()) {
    if (config.security_identity.empty()) {
      throw std::logic_error(
          "link: security on without an identity (LinkConfig::security_identity)");
    }
    // Missing files or an expired certificate: a clear line now, not a
    // silent participant that never authenticates.
    CheckSecurity(config.security, config.security_identity);
    for (const auto& [key, value] : SecurityProperties(config.security, config.security_identity)) {
      qos.properties().properties().emplace_back(key, value);
    }
  }
  if (!config.discovery_server.empty()) {
    // A client of the server: discovery goes through it alone.
    const auto [address, port] = ParseServerAddress(config.discovery_server);
    eprosima::fastdds::rtps::RemoteServerAttributes server;
    server.ReadguidPrefix(kServerPrefix);
    server.metatrafficUnicastLocatorList.push_back(UdpLocator(address, port));
    builtin.discovery_config.discoveryProtocol =
        eprosima::fastrtps::rtps::DiscoveryProtocol_t::CLIENT;
    builtin.discovery_config.m_DiscoveryServers.push_back(server);
    builtin.initialPeersList.clear();
  }
  // Announce often at start so processes meet quickly.
  builtin.discovery_config.initial_announcements.count = 10;
  builtin.discovery_config.initial_announcements.period = ToDuration(0.05);

  participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
      static_cast<dds::DomainId_t>(config.domain_id), qos, listener,
      // Discovery only: a participant's listener with the data statuses on
      // would take every reader's samples (on_data_on_readers) from it.
      listener != nullptr ? dds::StatusMask::none() : dds::StatusMask::all());
  if (participant_ == nullptr) {
    throw std::runtime_error("link: DDS refused to create participant '" + name + "' in domain " +
                             std::to_string(config.domain_id));
  }
  publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
  if (publisher_ == nullptr || subscriber_ == nullptr) {
    throw std::runtime_error("link: DDS refused to create a publisher or subscriber");
  }
}

Participant::~Participant() {
  // No delayed packet may reach a receiver the participant is tearing down.
  if (line_) line_->Shutdown();
  if (participant_ == nullptr) return;
  participant_->delete_contained_entities();
  dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

DiscoveryServer::DiscoveryServer(const std::string& address, int port) {
  LogToStderr();
  dds::DomainParticipantQos qos = dds::PARTICIPANT_QOS_DEFAULT;
  qos.name("haptel-discovery-server");
  auto& builtin = qos.wire_protocol().builtin;
  builtin.discovery_config.discoveryProtocol =
      eprosima::fastrtps::rtps::DiscoveryProtocol_t::SERVER;
  std::istringstream(kServerPrefix) >> qos.wire_protocol().prefix;
  builtin.metatrafficUnicastLocatorList.push_back(UdpLocator(address, port));
  participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(0, qos);
  if (participant_ == nullptr) {
    throw std::runtime_error("link: cannot serve discovery on " + address + ":" +
                             std::to_string(port) +
                             " (is the port taken, or the address not this host's?)");
  }
}

DiscoveryServer::~DiscoveryServer() {
  if (participant_ != nullptr)
    dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

}  // namespace haptel::link
