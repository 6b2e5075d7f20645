#pragma once
/// @file How a process joins the DDS link.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace haptel {

/// Faults injected into the link by the process's own DDS transport (a
/// chaining transport over UDP; shared memory, data sharing and
/// intra-process delivery are off while it is in, since they bypass any
/// transport). Each process delays and drops what it receives, so with the
/// same fault on both ends each direction gets it once. Written
/// "delay=100ms,jitter=20ms,loss=5%" (link.fault, --link-fault).
struct LinkFault {
  bool enabled = false;  ///< the fault transport is in (also for the link-down switch, SIGUSR1)
  double delay_s = 0.0;  ///< added to every packet received
  double jitter_s = 0.0; ///< each packet's delay varies uniformly by ± this (packets may reorder)
  double loss = 0.0;     ///< fraction of packets received that are dropped, in [0, 1)

  /// Throws ConfigFieldError ("delay_s", "loss") unless delay and jitter are
  /// in [0, 10] s and loss in [0, 0.99].
  void ValidateOrThrow() const;
};

/// Parses "delay=100ms,jitter=20ms,loss=5%" (any of the three, in any order;
/// times in s, ms or us; loss in % or as a fraction; "on" alone enables the
/// transport with no fault). Throws std::invalid_argument whose what() is
/// what was expected, naming the part that is not ("a loss from 0 to 99%,
/// such as 5% or 0.05 (not 'loss=200%')").
LinkFault ParseLinkFault(const std::string& text);
/// ParseLinkFault for the --link-fault option of haptel run and
/// haptel-vehicle: a UsageError ("option --link-fault: expected ...").
LinkFault ParseLinkFaultOption(const std::string& text);
/// A comma-separated list of IPv4 addresses for option `--option` (the
/// --dds-interfaces and --dds-peers of haptel run and haptel-vehicle):
/// a UsageError naming the option and the address that is not one.
std::vector<std::string> ParseAddressOption(const std::string& option, const std::string& text);
/// "ADDR:PORT" -> (IPv4 address, port 1..65535); throws std::invalid_argument
/// saying what was expected.
std::pair<std::string, int> ParseServerAddress(const std::string& text);
/// ParseServerAddress for the --discovery-server option: the text as given,
/// or a UsageError ("option --discovery-server: expected ...").
std::string ServerOption(const std::string& text);
/// The text ParseLinkFault reads back as `fault` (what a spawned vehicle is given).
std::string LinkFaultText(const LinkFault& fault);

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
  /// Injected faults (none by default).
  LinkFault fault;
  /// DDS Security (empty: off): the folder `haptel security init` made, with
  /// the CA, each identity's certificate, key and signed permissions, and the
  /// signed governance. `link.security` in a file is relative to that file.
  std::filesystem::path security;
  /// A Fast DDS discovery server to meet through, "ADDR:PORT" (empty: none;
  /// unicast discovery through `peers`): for networks without multicast
  /// where the hosts do not know each other's addresses, only the server's
  /// (`haptel discovery-server`).
  std::string discovery_server;
  /// Which identity of `security` this process is ("operator",
  /// "vehicle-robot1"): set by the program, never read from a file.
  std::string security_identity;

  /// Throws ConfigFieldError unless the domain and deadline are in range and
  /// every interface and peer is a dotted IPv4 address ("peers[1]").
  void ValidateOrThrow() const;
};

}  // namespace haptel
