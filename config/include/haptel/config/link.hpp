#pragma once
/// @file How a process joins the DDS link.
#include <string>
#include <vector>

namespace haptel {

struct LinkConfig {
  /// DDS domain; processes meet only inside one domain (0..232).
  int domain_id = 0;
  /// Network interfaces DDS may use. Loopback by default, so nothing leaves
  /// the host unless a deployment says so.
  std::vector<std::string> interfaces{"127.0.0.1"};
  /// Unicast discovery peers (hosts where other participants live).
  std::vector<std::string> peers{"127.0.0.1"};
  /// Command topic deadline: a writer or reader that misses it is reported.
  double command_deadline_s = 0.1;

  /// Throws ConfigFieldError unless the domain and deadline are in range and
  /// every interface and peer is a dotted IPv4 address ("peers[1]").
  void ValidateOrThrow() const;
};

}  // namespace haptel
