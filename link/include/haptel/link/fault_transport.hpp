#pragma once
/// @file Faults injected into a participant's own transport (LinkFault): a
/// Fast DDS ChainingTransport over UDPv4 that drops and delays what it
/// receives, and drops everything both ways while the link is down.
///
/// The kernel here has no netem, so the link's faults live in the process:
/// each participant's transport delays (delay ± jitter, uniformly; packets
/// may overtake each other, as on a real network) and drops (loss) the
/// packets it receives, discovery included. With a rate, a packet first
/// waits its turn in a drop-tail FIFO served at that rate (RateQueue), then
/// the delay line holds it (netem behind tbf). Both ends faulted alike give
/// each direction the fault once. A FaultLine's thread delivers the delayed
/// packets when due; it is shut down before its participant is deleted, so
/// no packet reaches a receiver being torn down.
#include <fastdds/rtps/transport/TransportDescriptorInterface.h>
#include <fastdds/rtps/transport/TransportReceiverInterface.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <queue>
#include <random>
#include <thread>
#include <vector>

#include "haptel/config/link.hpp"

namespace haptel::link {

/// The link-down switch: while it is set, every fault transport of the
/// process sends and delivers nothing (the link is cut both ways).
void SetLinkDown(bool down);
bool LinkDown();
/// SIGUSR1 toggles the link-down switch (what a test or an operator sends to
/// a process started with a link fault). Async-signal-safe.
void InstallLinkDownSignal();

/// What a participant's fault transports did.
struct FaultCounts {
  uint64_t received = 0;             ///< packets that reached the transport
  uint64_t lost = 0;                 ///< dropped by `loss`
  uint64_t delayed = 0;              ///< delivered late by the delay line
  uint64_t dropped_down = 0;         ///< dropped, in or out, while the link was down
  uint64_t queue_dropped = 0;        ///< dropped by the rate's full queue (drop-tail)
  uint64_t queue_dropped_bytes = 0;  ///< their bytes
};

/// The rate stage of a link fault: a queue served at `rate_bps`, whose
/// packets each take size × 8 / rate to pass, and which drops an arriving
/// packet that would wait longer than `queue_s` for its turn (drop-tail,
/// with the depth in time as tc's tbf `latency`).
///
/// Two classes, strictly prioritised, as a link with DiffServ's expedited
/// forwarding for control traffic would: small packets (at most
/// kUrgentMaxBytes: commands, states, acknowledgements, heartbeats and
/// discovery are all under it; video frames are kilobytes) go ahead of the
/// bulk queue, waiting only for each other and for at most one MTU of bulk
/// already on the wire. So a saturated video stream does not queue a
/// command behind it (issue 24: "commands and states come first"); what
/// the urgent class sends still takes its share of the rate from the bulk
/// class behind it. A video frame small enough to pass as urgent (below
/// ~100 kbit/s) is then served with the commands, in their order.
///
/// Kept in virtual time: a packet's departure is known when it arrives, so
/// no thread serves the queue (the delay line delivers it then); a bulk
/// packet already admitted keeps its departure when an urgent one passes it
/// (the bulk queue behind it is pushed back instead). Not thread-safe;
/// times are any monotonic clock's, in ns.
class RateQueue {
 public:
  /// Packets of at most this size are urgent.
  static constexpr size_t kUrgentMaxBytes = 600;
  /// What of a bulk packet on the wire an urgent one may wait for.
  static constexpr size_t kMtuBytes = 1500;

  RateQueue(double rate_bps, double queue_s);
  /// A packet of `bytes` arriving at `now_ns`: when its last bit has passed,
  /// or nothing when it is dropped (the queue ahead of it is deeper than
  /// `queue_s`).
  std::optional<int64_t> Admit(int64_t now_ns, size_t bytes);
  /// From now on, packets pass at `rate_bps` (> 0); those already admitted
  /// keep their departures, as a link whose rate changes under its queue
  /// (tc's `tbf change`). The queue's depth in time stays.
  void SetRate(double rate_bps) { ns_per_byte_ = 8e9 / rate_bps; }
  double rate_bps() const { return 8e9 / ns_per_byte_; }
  /// How long a bulk packet arriving at `now_ns` would wait for its turn.
  int64_t WaitNs(int64_t now_ns) const {
    const int64_t free_at = std::max(free_at_ns_, urgent_free_at_ns_);
    return free_at > now_ns ? free_at - now_ns : 0;
  }

 private:
  double ns_per_byte_;
  int64_t max_wait_ns_;
  int64_t free_at_ns_ = 0;         ///< when the bulk queue has passed
  int64_t urgent_free_at_ns_ = 0;  ///< when the urgent queue has passed
};

/// A participant's delay line and dice, shared by its transports.
class FaultLine {
 public:
  /// `seed`: the loss and jitter draws (a fixed seed repeats a run's faults).
  FaultLine(const LinkFault& fault, uint64_t seed);
  ~FaultLine();
  FaultLine(const FaultLine&) = delete;
  FaultLine& operator=(const FaultLine&) = delete;

  /// Stops the delivering thread and drops what is still queued; afterwards
  /// every packet is dropped. Idempotent.
  void Shutdown();
  FaultCounts Counts() const;

  /// Changes the rate stage at run time, from any thread: packets arriving
  /// from now on pass at `rate_bps` (0: no limit), behind those already
  /// queued. A line made without a rate gains one (the queue's depth is the
  /// LinkFault's `queue_s`). For a capacity schedule (`haptel bench video`):
  /// the fault is on what this process receives, so the operator's own line
  /// sets the rate its video arrives at, and nothing crosses processes.
  /// Throws std::invalid_argument for a negative or non-finite rate.
  void SetRate(double rate_bps);
  /// The rate now, bit/s (0: no limit).
  double rate_bps() const;

  /// A packet the transport received: dropped, delivered now, or queued.
  void Receive(eprosima::fastdds::rtps::TransportReceiverInterface* next, const uint8_t* data,
               uint32_t size, const eprosima::fastrtps::rtps::Locator_t& local,
               const eprosima::fastrtps::rtps::Locator_t& remote);
  /// Whether a packet about to be sent is dropped (the link is down).
  bool DropSend();

  /// The transport's own capture (what a packet capture would see on the
  /// wire): from now on, keep a copy of up to `max_packets` packets as they
  /// arrive, before any fault. TakeCaptured hands them over.
  void CaptureReceived(size_t max_packets);
  std::vector<std::vector<uint8_t>> TakeCaptured();

 private:
  struct Packet {
    int64_t due_ns = 0;
    uint64_t order = 0;  ///< ties keep their arrival order
    std::vector<uint8_t> data;
    eprosima::fastrtps::rtps::Locator_t local;
    eprosima::fastrtps::rtps::Locator_t remote;
    eprosima::fastdds::rtps::TransportReceiverInterface* next = nullptr;
    bool operator>(const Packet& other) const {
      return due_ns != other.due_ns ? due_ns > other.due_ns : order > other.order;
    }
  };
  void Deliver();

  LinkFault fault_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::priority_queue<Packet, std::vector<Packet>, std::greater<>> queue_;
  std::mt19937_64 random_;
  uint64_t order_ = 0;
  bool stopped_ = false;
  std::atomic<size_t> capture_max_{0};
  std::vector<std::vector<uint8_t>> captured_;
  std::optional<RateQueue> rate_;  ///< with LinkFault::rate_bps
  std::atomic<uint64_t> received_{0}, lost_{0}, delayed_{0}, dropped_down_{0}, queue_dropped_{0},
      queue_dropped_bytes_{0};
  std::thread thread_;  // last: it uses the rest
};

/// The transport descriptor to put in a participant's user transports:
/// `udp` wrapped in the fault transport feeding `line`.
std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> MakeFaultTransport(
    std::shared_ptr<eprosima::fastdds::rtps::UDPv4TransportDescriptor> udp,
    std::shared_ptr<FaultLine> line);

}  // namespace haptel::link
