#include "haptel/link/fault_transport.hpp"

#include <fastdds/rtps/transport/ChainingTransport.h>
#include <fastdds/rtps/transport/ChainingTransportDescriptor.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "haptel/core/clock.hpp"

namespace haptel::link {

namespace rtps = eprosima::fastdds::rtps;
using eprosima::fastrtps::rtps::Locator_t;
using eprosima::fastrtps::rtps::octet;

namespace {

std::atomic<bool> g_link_down{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler sets it");

void ToggleLinkDown(int) { g_link_down.store(!g_link_down.load()); }

struct FaultDescriptor;

class FaultTransport : public rtps::ChainingTransport {
 public:
  explicit FaultTransport(const FaultDescriptor& descriptor);

  rtps::TransportDescriptorInterface* get_configuration() override;

  bool send(eprosima::fastrtps::rtps::SenderResource* low_sender_resource, const octet* send_buffer,
            uint32_t send_buffer_size,
            eprosima::fastrtps::rtps::LocatorsIterator* destination_locators_begin,
            eprosima::fastrtps::rtps::LocatorsIterator* destination_locators_end,
            const std::chrono::steady_clock::time_point& timeout) override {
    if (line_->DropSend()) return true;  // cut: as good as sent, and lost
    return low_sender_resource->send(send_buffer, send_buffer_size, destination_locators_begin,
                                     destination_locators_end, timeout);
  }

  void receive(rtps::TransportReceiverInterface* next_receiver, const octet* receive_buffer,
               uint32_t receive_buffer_size, const Locator_t& local_locator,
               const Locator_t& remote_locator) override {
    line_->Receive(next_receiver, receive_buffer, receive_buffer_size, local_locator,
                   remote_locator);
  }

 private:
  std::unique_ptr<FaultDescriptor> descriptor_;
  std::shared_ptr<FaultLine> line_;
};

struct FaultDescriptor : public rtps::ChainingTransportDescriptor {
  FaultDescriptor(std::shared_ptr<rtps::TransportDescriptorInterface> low,
                  std::shared_ptr<FaultLine> fault_line)
      : ChainingTransportDescriptor(std::move(low)), line(std::move(fault_line)) {}
  rtps::TransportInterface* create_transport() const override { return new FaultTransport(*this); }
  std::shared_ptr<FaultLine> line;
};

FaultTransport::FaultTransport(const FaultDescriptor& descriptor)
    : ChainingTransport(descriptor),
      descriptor_(std::make_unique<FaultDescriptor>(descriptor)),
      line_(descriptor.line) {}

rtps::TransportDescriptorInterface* FaultTransport::get_configuration() {
  return descriptor_.get();
}

}  // namespace

void SetLinkDown(bool down) { g_link_down.store(down); }
bool LinkDown() { return g_link_down.load(); }

void InstallLinkDownSignal() {
  struct sigaction action {};
  action.sa_handler = ToggleLinkDown;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESTART;
  sigaction(SIGUSR1, &action, nullptr);
}

RateQueue::RateQueue(double rate_bps, double queue_s)
    : ns_per_byte_(8e9 / rate_bps), max_wait_ns_(SToNs(queue_s)) {}

std::optional<int64_t> RateQueue::Admit(int64_t now_ns, size_t bytes) {
  const auto take = [&](size_t n) {
    return static_cast<int64_t>(std::llround(static_cast<double>(n) * ns_per_byte_));
  };
  const int64_t cost = take(bytes);
  if (bytes > kUrgentMaxBytes) {
    const int64_t start = std::max({now_ns, free_at_ns_, urgent_free_at_ns_});
    if (start - now_ns > max_wait_ns_) return std::nullopt;
    free_at_ns_ = start + cost;
    return free_at_ns_;
  }
  // Urgent: behind the urgent queue and what is left of one bulk MTU on
  // the wire, not behind the whole bulk queue.
  const int64_t on_wire = std::min(std::max<int64_t>(free_at_ns_ - now_ns, 0), take(kMtuBytes));
  const int64_t start = std::max(now_ns + on_wire, urgent_free_at_ns_);
  if (start - now_ns > max_wait_ns_) return std::nullopt;
  urgent_free_at_ns_ = start + cost;
  // The rate it took is the bulk queue's loss: what waits there (and
  // whatever comes next) passes that much later.
  free_at_ns_ = free_at_ns_ > now_ns ? free_at_ns_ + cost : urgent_free_at_ns_;
  return urgent_free_at_ns_;
}

FaultLine::FaultLine(const LinkFault& fault, uint64_t seed) : fault_(fault), random_(seed) {
  if (fault.rate_bps > 0.0) rate_.emplace(fault.rate_bps, fault.queue_s);
  thread_ = std::thread([this] { Deliver(); });
}

FaultLine::~FaultLine() { Shutdown(); }

void FaultLine::Shutdown() {
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    stopped_ = true;
    queue_ = {};
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void FaultLine::SetRate(double rate_bps) {
  if (!(rate_bps >= 0.0) || !std::isfinite(rate_bps)) {
    throw std::invalid_argument("link fault: rate " + std::to_string(rate_bps) +
                                " bit/s, expected 0 (no limit) or more");
  }
  std::lock_guard lock(mutex_);
  fault_.rate_bps = rate_bps;
  if (rate_bps == 0.0) {
    rate_.reset();
  } else if (rate_) {
    rate_->SetRate(rate_bps);
  } else {
    rate_.emplace(rate_bps, fault_.queue_s);
  }
}

double FaultLine::rate_bps() const {
  std::lock_guard lock(mutex_);
  return rate_ ? rate_->rate_bps() : 0.0;
}

FaultCounts FaultLine::Counts() const {
  return {received_.load(),     lost_.load(),          delayed_.load(),
          dropped_down_.load(), queue_dropped_.load(), queue_dropped_bytes_.load()};
}

bool FaultLine::DropSend() {
  if (!LinkDown()) return false;
  dropped_down_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

void FaultLine::CaptureReceived(size_t max_packets) {
  std::lock_guard lock(mutex_);
  capture_max_ = max_packets;
  captured_.reserve(max_packets);
}

std::vector<std::vector<uint8_t>> FaultLine::TakeCaptured() {
  std::lock_guard lock(mutex_);
  std::vector<std::vector<uint8_t>> out;
  out.swap(captured_);
  return out;
}

void FaultLine::Receive(rtps::TransportReceiverInterface* next, const uint8_t* data, uint32_t size,
                        const Locator_t& local, const Locator_t& remote) {
  received_.fetch_add(1, std::memory_order_relaxed);
  if (capture_max_ > 0) {
    std::lock_guard lock(mutex_);
    if (captured_.size() < capture_max_) captured_.emplace_back(data, data + size);
  }
  if (LinkDown()) {
    dropped_down_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  double delay_s = fault_.delay_s;
  {
    std::lock_guard lock(mutex_);
    if (stopped_) return;
    if (fault_.loss > 0.0 &&
        std::uniform_real_distribution<double>(0.0, 1.0)(random_) < fault_.loss) {
      lost_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    const int64_t now = MonotonicNs();
    int64_t passed_ns = now;  // when the rate stage lets it go
    if (rate_) {
      const std::optional<int64_t> passed = rate_->Admit(now, size);
      if (!passed) {
        queue_dropped_.fetch_add(1, std::memory_order_relaxed);
        queue_dropped_bytes_.fetch_add(size, std::memory_order_relaxed);
        return;
      }
      passed_ns = *passed;
    }
    if (fault_.jitter_s > 0.0) {
      delay_s += std::uniform_real_distribution<double>(-fault_.jitter_s, fault_.jitter_s)(random_);
    }
    if (delay_s > 0.0 || passed_ns > now) {
      Packet p;
      p.due_ns = passed_ns + SToNs(std::max(delay_s, 0.0));
      p.order = order_++;
      p.data.assign(data, data + size);
      p.local = local;
      p.remote = remote;
      p.next = next;
      queue_.push(std::move(p));
      wake_.notify_one();
      return;
    }
  }
  next->OnDataReceived(data, size, local, remote);
}

void FaultLine::Deliver() {
  std::unique_lock lock(mutex_);
  while (!stopped_) {
    if (queue_.empty()) {
      wake_.wait(lock);
      continue;
    }
    const int64_t due = queue_.top().due_ns;
    const int64_t now = MonotonicNs();
    if (due > now) {
      wake_.wait_for(lock, std::chrono::nanoseconds(due - now));
      continue;
    }
    Packet p = std::move(const_cast<Packet&>(queue_.top()));
    queue_.pop();
    lock.unlock();
    // The link may have gone down while the packet was on its way.
    if (LinkDown()) {
      dropped_down_.fetch_add(1, std::memory_order_relaxed);
    } else {
      delayed_.fetch_add(1, std::memory_order_relaxed);
      p.next->OnDataReceived(p.data.data(), static_cast<uint32_t>(p.data.size()), p.local,
                             p.remote);
    }
    lock.lock();
  }
}

std::shared_ptr<rtps::TransportDescriptorInterface> MakeFaultTransport(
    std::shared_ptr<rtps::UDPv4TransportDescriptor> udp, std::shared_ptr<FaultLine> line) {
  return std::make_shared<FaultDescriptor>(std::move(udp), std::move(line));
}

}  // namespace haptel::link
