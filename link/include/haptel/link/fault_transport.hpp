#pragma once
/// @file Faults injected into a participant's own transport (LinkFault): a
/// Fast DDS ChainingTransport over UDPv4 that drops and delays what it
/// receives, and drops everything both ways while the link is down.
///
/// The kernel here has no netem, so the link's faults live in the process:
/// each participant's transport delays (delay ± jitter, uniformly; packets
/// may overtake each other, as on a real network) and drops (loss) the
/// packets it receives, discovery included. Both ends faulted alike give
/// each direction the fault once. A FaultLine's thread delivers the delayed
/// packets when due; it is shut down before its participant is deleted, so
/// no packet reaches a receiver being torn down.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <queue>
#include <random>
#include <thread>
#include <vector>

#include <fastdds/rtps/transport/TransportDescriptorInterface.h>
#include <fastdds/rtps/transport/TransportReceiverInterface.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>

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
  uint64_t received = 0;      ///< packets that reached the transport
  uint64_t lost = 0;          ///< dropped by `loss`
  uint64_t delayed = 0;       ///< delivered late by the delay line
  uint64_t dropped_down = 0;  ///< dropped, in or out, while the link was down
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

  /// A packet the transport received: dropped, delivered now, or queued.
  void Receive(eprosima::fastdds::rtps::TransportReceiverInterface* next, const uint8_t* data, uint32_t size,
               const eprosima::fastrtps::rtps::Locator_t& local, const eprosima::fastrtps::rtps::Locator_t& remote);
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
  std::atomic<uint64_t> received_{0}, lost_{0}, delayed_{0}, dropped_down_{0};
  std::thread thread_;  // last: it uses the rest
};

/// The transport descriptor to put in a participant's user transports:
/// `udp` wrapped in the fault transport feeding `line`.
std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> MakeFaultTransport(
    std::shared_ptr<eprosima::fastdds::rtps::UDPv4TransportDescriptor> udp, std::shared_ptr<FaultLine> line);

}  // namespace haptel::link
