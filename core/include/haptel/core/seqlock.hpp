#pragma once
/// @file Single-writer "latest value" hand-off that never blocks the writer.
///
/// The writer bumps a sequence number to odd, stores the value, and bumps it
/// to even; a reader retries while the sequence is odd or changed under it.
/// The payload is kept in atomic words, so the copy is data-race free in the
/// C++ memory model (no torn reads are ever returned).
///
/// Ordering: each payload word is stored with release and loaded with
/// acquire (Boehm, "Can seqlocks get along with programming language memory
/// models?", 2012), instead of relaxed words between standalone fences. A
/// reader that sees any word of a newer store therefore also sees that
/// store's odd sequence number and retries. On x86-64 both are plain moves,
/// as the fences were; unlike fences, ThreadSanitizer understands them
/// (GCC warns, -Wtsan, that it does not model atomic_thread_fence).
///
/// Load() retries for as long as a store is in progress: right for slower
/// threads. A real-time reader uses TryLoad(), which gives up after a few
/// attempts — a writer pre-empted mid-store on a shared core under SCHED_FIFO
/// would otherwise stall it until the writer runs again — and keeps its last
/// good value instead.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace haptel {

template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>, "Seqlock needs a trivially copyable T");

 public:
  Seqlock() { Store(T{}); }
  explicit Seqlock(const T& initial) { Store(initial); }

  /// Publishes a new value. One writer thread only. Wait-free.
  void Store(const T& value) {
    Words words{};
    std::memcpy(words.data(), &value, sizeof(T));
    const uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);
    // Release: a reader that loads this word also sees the odd number above.
    for (size_t i = 0; i < kWords; ++i) data_[i].store(words[i], std::memory_order_release);
    seq_.store(seq + 2, std::memory_order_release);
  }

  /// Returns the latest complete value. Any number of readers; lock-free
  /// but not wait-free: it retries while a store is in progress.
  T Load() const {
    Words words{};
    while (!TryCopy(words)) {
    }
    return FromWords(words);
  }

  /// Attempts a complete read at most `max_attempts` (>= 1) times. On success
  /// writes the value into `out` and returns true; when every attempt met a
  /// store in progress (or overtaken by one) leaves `out` untouched and
  /// returns false, so a caller that keeps its last good value in `out`
  /// simply goes on with it. Wait-free: bounded by `max_attempts`.
  bool TryLoad(T& out, int max_attempts) const {
    Words words{};
    for (int attempt = 0; attempt < max_attempts; ++attempt) {
      if (TryCopy(words)) {
        out = FromWords(words);
        return true;
      }
    }
    return false;
  }

  /// Number of completed stores; lets a reader tell whether a value is new.
  uint64_t Version() const { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  static constexpr size_t kWords = (sizeof(T) + sizeof(uint64_t) - 1) / sizeof(uint64_t);
  using Words = std::array<uint64_t, kWords>;
  /// Tests hold a store half done through this (it may set seq_ odd).
  friend struct SeqlockTestAccess;

  /// One read attempt: true when `words` holds a complete value.
  bool TryCopy(Words& words) const {
    const uint64_t before = seq_.load(std::memory_order_acquire);
    if ((before & 1U) != 0) return false;  // a store is in progress
    // Acquire: the check below cannot move before these loads.
    for (size_t i = 0; i < kWords; ++i) words[i] = data_[i].load(std::memory_order_acquire);
    return seq_.load(std::memory_order_relaxed) == before;
  }

  static T FromWords(const Words& words) {
    T value;
    std::memcpy(static_cast<void*>(&value), words.data(), sizeof(T));
    return value;
  }
  std::atomic<uint64_t> seq_{0};
  std::array<std::atomic<uint64_t>, kWords> data_{};
};

}  // namespace haptel
