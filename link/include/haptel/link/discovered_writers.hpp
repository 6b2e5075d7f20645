#pragma once
/// @file The writers DDS discovers on a domain: their topics and type names.
///
/// A participant's listener (pass it to link::Participant; it must outlive
/// the participant). DDS calls it on its discovery thread; the owner reads
/// on its own. `haptel record` finds the domain's topics through it, and a
/// run sees at once a vehicle of another kind answering under the name it
/// drives (its state topic carries another type, which never matches).
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <mutex>
#include <string>
#include <vector>

namespace haptel::link {

struct DiscoveredWriter {
  std::string topic;
  std::string type;  ///< the DDS type name, e.g. "haptel::msg::VehicleState"
};

class DiscoveredWriters : public eprosima::fastdds::dds::DomainParticipantListener {
 public:
  void on_publisher_discovery(eprosima::fastdds::dds::DomainParticipant*,
                              eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) override;

  /// The writers found since the last call (each once per discovery).
  std::vector<DiscoveredWriter> Take();
  /// The type of the first writer found on `topic` whose type is not
  /// `expected` ("" when there is none).
  std::string OtherTypeOn(const std::string& topic, const std::string& expected) const;

 private:
  mutable std::mutex mutex_;
  std::vector<DiscoveredWriter> new_;
  std::vector<DiscoveredWriter> all_;
};

}  // namespace haptel::link
