#pragma once
/// @file How a process joins the DDS link.
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "haptel/config/archive.hpp"

namespace haptel {

/// Faults injected into the link by the process's own DDS transport (a
/// chaining transport over UDP; shared memory, data sharing and
/// intra-process delivery are off while it is in, since they bypass any
/// transport). Each process delays and drops what it receives, so with the
/// same fault on both ends each direction gets it once. Written
/// "rate=1Mbit,delay=100ms,jitter=20ms,loss=5%" (link.fault, --link-fault).
///
/// The stages compose as netem behind tbf does: a packet first waits its
/// turn at the rate (a drop-tail FIFO served at `rate_bps`), then is
/// delayed by delay ± jitter; loss is drawn before either.
struct LinkFault {
  bool enabled = false;   ///< the fault transport is in (also for the link-down switch, SIGUSR1)
  double delay_s = 0.0;   ///< added to every packet received
  double jitter_s = 0.0;  ///< each packet's delay varies uniformly by ± this (packets may reorder)
  double loss = 0.0;      ///< fraction of packets received that are dropped, in [0, 1)
  /// The rate the received packets are served at, bit/s (0: no limit): each
  /// takes its size × 8 / rate to pass, after those ahead of it.
  double rate_bps = 0.0;
  /// The drop-tail queue's depth in time at `rate_bps`: a packet that would
  /// wait longer than this before its turn is dropped (a tc tbf's latency).
  double queue_s = 0.1;

  /// Throws ConfigFieldError ("delay_s", "loss", "rate_bps", "queue_s")
  /// unless delay and jitter are in [0, 10] s, loss in [0, 0.99], the rate 0
  /// or in [1 kbit/s, 10 Gbit/s] and the queue in [1 ms, 10 s].
  void ValidateOrThrow() const;
};

/// Parses "rate=1Mbit,queue=100ms,delay=100ms,jitter=20ms,loss=5%" (any of
/// them, in any order; times in s, ms or us; rates in kbit, Mbit or Gbit
/// per second; loss in % or as a fraction; "on" alone enables the transport
/// with no fault). The keys given override `base`'s (a link profile's);
/// the rest keep its values. Throws std::invalid_argument whose what() is
/// what was expected, naming the part that is not ("a loss from 0 to 99%,
/// such as 5% or 0.05 (not 'loss=200%')").
LinkFault ParseLinkFault(const std::string& text, const LinkFault& base = {});
/// ParseLinkFault for the --link-fault option of haptel run and
/// haptel-vehicle: a UsageError ("option --link-fault: expected ...").
LinkFault ParseLinkFaultOption(const std::string& text, const LinkFault& base = {});

/// The link profiles shipped in config/links/ ("lan", "lte-uplink", ...),
/// sorted by name.
std::vector<std::string> LinkProfileNames();
/// A link profile: a shipped one by name ("lte-uplink" is
/// config/links/lte-uplink.yaml), or a file (a name with a '/' or ending in
/// .yaml). The file holds rate, queue, delay, jitter and loss, written as in
/// ParseLinkFault ("rate: 2Mbit", "loss: 1%"); every key is optional.
/// Throws ConfigError naming the file and key, or, for a name that is not
/// shipped, the names that are.
LinkFault LoadLinkProfile(const std::string& name_or_file);
/// What makes `fault` impossible to drive through, "" when nothing does:
/// states sent at `state_rate_hz`, a vehicle silent for `vehicle_timeout_s`
/// is lost. A loss so high that a whole time-out's states are all dropped
/// more than once a minute (on average), or a jitter that holds a state back
/// longer than the time-out, would end the run as a vehicle lost (or one that
/// never answered) though the vehicle runs: said instead, before it starts.
std::string LinkFaultProblem(const LinkFault& fault, double state_rate_hz,
                             double vehicle_timeout_s);

/// --link-profile and --link-fault together (either may be absent): the
/// profile, then the keys --link-fault names over it; `otherwise` when
/// neither is given. A bad profile or fault is a UsageError naming its
/// option and what was expected.
LinkFault LinkFaultFromOptions(const std::optional<std::string>& profile,
                               const std::optional<std::string>& fault, const LinkFault& otherwise);
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

  template <typename Archive>
  void Serialize(Archive* a) {
    // Every field but security_identity (the program's, never a file's).
    a->Visit(HAPTEL_NVP(domain_id), config::Range{0, 232});
    a->Visit(HAPTEL_NVP(interfaces));
    a->Visit(HAPTEL_NVP(peers));
    a->Visit(HAPTEL_NVP(command_deadline_s), config::Range{0.001, 10.0});
    a->Visit(HAPTEL_NVP(fault), config::AsText<LinkFault>{&ParseLinkFault, &LinkFaultText});
    a->Visit(HAPTEL_NVP(security), config::RelativeToFile{});
    a->Visit(HAPTEL_NVP(discovery_server));
  }

  /// Throws ConfigFieldError unless the domain and deadline are in range and
  /// every interface and peer is a dotted IPv4 address ("peers[1]").
  void ValidateOrThrow() const;
};

}  // namespace haptel
