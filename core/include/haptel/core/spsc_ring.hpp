#pragma once
/// @file Single-producer, single-consumer ring for streams between a real-time
/// thread and a slower one. Fixed capacity, allocated once; Push and Pop are
/// wait-free and never allocate. A full ring refuses the push (the producer
/// counts the drop) rather than blocking.
#include <atomic>
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <type_traits>

namespace haptel {

template <typename T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds trivially copyable values");

 public:
  /// @param capacity slots; rounded up to a power of two.
  explicit SpscRing(size_t capacity) {
    if (capacity == 0) throw std::invalid_argument("SpscRing: capacity must be > 0");
    size_ = 1;
    while (size_ < capacity) size_ <<= 1;
    slots_ = std::make_unique<T[]>(size_);
  }

  /// Producer thread only. False when full.
  bool Push(const T& value) {
    const size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) == size_) return false;
    slots_[head & (size_ - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer thread only. False when empty.
  bool Pop(T& out) {
    const size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return false;
    out = slots_[tail & (size_ - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  size_t capacity() const { return size_; }

 private:
  size_t size_ = 0;
  std::unique_ptr<T[]> slots_;
  alignas(64) std::atomic<size_t> head_{0};
  alignas(64) std::atomic<size_t> tail_{0};
};

}  // namespace haptel
