#include "haptel/config/link.hpp"

#include <arpa/inet.h>

#include "haptel/config/check.hpp"

namespace haptel {

namespace check = config_check;

namespace {
/// Every element of `addresses` (the list under `key`) is a dotted IPv4
/// address: DDS would otherwise drop a bad interface silently (nothing is
/// ever heard) or fail only once the vehicle is spawned.
void CheckIpv4List(const std::string& key, const std::vector<std::string>& addresses) {
  for (size_t i = 0; i < addresses.size(); ++i) {
    in_addr parsed{};
    if (inet_pton(AF_INET, addresses[i].c_str(), &parsed) != 1) {
      check::Fail(key + "[" + std::to_string(i) + "]", "an IPv4 address such as 127.0.0.1");
    }
  }
}
}  // namespace

void LinkConfig::ValidateOrThrow() const {
  check::Whole("domain_id", domain_id, 0, 232);
  CheckIpv4List("interfaces", interfaces);
  CheckIpv4List("peers", peers);
  check::Number("command_deadline_s", command_deadline_s, 0.001, 10.0);
}

}  // namespace haptel
