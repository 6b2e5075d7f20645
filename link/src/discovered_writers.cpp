#include "haptel/link/discovered_writers.hpp"

#include <utility>

namespace haptel::link {

void DiscoveredWriters::on_publisher_discovery(
    eprosima::fastdds::dds::DomainParticipant*,
    eprosima::fastrtps::rtps::WriterDiscoveryInfo&& info) {
  if (info.status != eprosima::fastrtps::rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
  DiscoveredWriter found{info.info.topicName().to_string(), info.info.typeName().to_string()};
  std::lock_guard lock(mutex_);
  all_.push_back(found);
  new_.push_back(std::move(found));
}

std::vector<DiscoveredWriter> DiscoveredWriters::Take() {
  std::lock_guard lock(mutex_);
  return std::exchange(new_, {});
}

std::string DiscoveredWriters::OtherTypeOn(const std::string& topic,
                                           const std::string& expected) const {
  std::lock_guard lock(mutex_);
  for (const DiscoveredWriter& w : all_) {
    if (w.topic == topic && w.type != expected) return w.type;
  }
  return "";
}

}  // namespace haptel::link
