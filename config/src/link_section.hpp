#pragma once
#include <arpa/inet.h>

#include "haptel/config/link.hpp"
#include "yaml_map.hpp"

namespace haptel::config_detail {

/// Every element of `addresses` (the list under `key`) is a dotted IPv4
/// address: DDS would otherwise drop a bad interface silently (nothing is
/// ever heard) or fail only once the vehicle is spawned.
inline void CheckIpv4List(const YamlMap& link, const std::string& key,
                          const std::vector<std::string>& addresses) {
  for (size_t i = 0; i < addresses.size(); ++i) {
    in_addr parsed{};
    if (inet_pton(AF_INET, addresses[i].c_str(), &parsed) != 1) {
      link.FailItem(key, i, "an IPv4 address such as 127.0.0.1");
    }
  }
}

/// Reads a `link:` section (and finishes it).
inline LinkConfig ReadLink(YamlMap& link) {
  LinkConfig c;
  c.domain_id = link.Integer("domain_id", c.domain_id, 0, 232);
  c.interfaces = link.Strings("interfaces", c.interfaces);
  CheckIpv4List(link, "interfaces", c.interfaces);
  c.peers = link.Strings("peers", c.peers);
  CheckIpv4List(link, "peers", c.peers);
  c.command_deadline_s = link.Number("command_deadline_s", c.command_deadline_s, 0.001, 10.0);
  link.Finish();
  return c;
}

}  // namespace haptel::config_detail
