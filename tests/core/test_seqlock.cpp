// Seqlock: a single writer publishes, readers always see a complete value.
#include <atomic>
#include <catch2/catch.hpp>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "haptel/core/seqlock.hpp"
#include "seqlock_access.hpp"
#include "test_env.hpp"

namespace {

// Every field carries the same counter, so a torn read shows as unequal fields.
struct Sample {
  uint64_t ints[4];
  double reals[4];
};

Sample MakeSample(uint64_t i) {
  Sample s{};
  for (auto& v : s.ints) v = i;
  for (auto& v : s.reals) v = static_cast<double>(i);
  return s;
}

bool Consistent(const Sample& s) {
  for (const auto& v : s.ints) {
    if (v != s.ints[0]) return false;
  }
  for (const auto& v : s.reals) {
    if (v != static_cast<double>(s.ints[0])) return false;
  }
  return true;
}

// A size that is not a multiple of the 8-byte word the seqlock copies in.
struct Odd {
  float x;
  float y;
  float z;
};

}  // namespace

TEST_CASE("Seqlock: default construction holds a value-initialised T", "[seqlock]") {
  haptel::Seqlock<Sample> lock;
  const Sample s = lock.Load();
  for (const auto& v : s.ints) CHECK(v == 0);
  for (const auto& v : s.reals) CHECK(v == 0.0);
}

TEST_CASE("Seqlock: single-threaded store and load round-trip", "[seqlock]") {
  haptel::Seqlock<Sample> lock(MakeSample(7));
  CHECK(lock.Load().ints[2] == 7);
  CHECK(Consistent(lock.Load()));

  for (uint64_t i : {1u, 42u, 1000u, 3u}) {
    lock.Store(MakeSample(i));
    const Sample s = lock.Load();
    CHECK(Consistent(s));
    CHECK(s.ints[0] == i);
    CHECK(s.reals[3] == static_cast<double>(i));
  }
}

TEST_CASE("Seqlock: a payload that is not a whole number of words round-trips", "[seqlock]") {
  haptel::Seqlock<Odd> lock(Odd{1.5f, -2.25f, 3.0f});
  Odd v = lock.Load();
  CHECK(v.x == 1.5f);
  CHECK(v.y == -2.25f);
  CHECK(v.z == 3.0f);
  lock.Store(Odd{-7.0f, 0.125f, 1e6f});
  v = lock.Load();
  CHECK(v.x == -7.0f);
  CHECK(v.y == 0.125f);
  CHECK(v.z == 1e6f);
}

TEST_CASE("Seqlock: Version() increments once per store", "[seqlock]") {
  haptel::Seqlock<Sample> lock;
  const uint64_t v0 = lock.Version();
  lock.Store(MakeSample(1));
  CHECK(lock.Version() == v0 + 1);
  lock.Store(MakeSample(2));
  lock.Store(MakeSample(2));  // same value again still counts as a store
  CHECK(lock.Version() == v0 + 3);
  (void)lock.Load();  // reading does not change the version
  CHECK(lock.Version() == v0 + 3);
}

TEST_CASE("Seqlock: concurrent readers never see a torn or older value", "[seqlock][threads]") {
  constexpr uint64_t kStores = 200'000;
  constexpr int kReaders = 2;
  haptel::Seqlock<Sample> lock(MakeSample(0));
  std::atomic<bool> done{false};
  std::atomic<int> started{0};

  struct ReaderResult {
    uint64_t loads = 0;
    uint64_t torn = 0;
    uint64_t backwards = 0;
    uint64_t version_backwards = 0;
    uint64_t older_than_version = 0;
    uint64_t last = 0;
  };
  // Store i makes the version base + i, so a load that follows a version read
  // of base + k must return a value of at least k.
  const uint64_t base = lock.Version();
  std::vector<ReaderResult> results(kReaders);
  std::vector<std::unique_ptr<haptel::test::Thread>> readers;
  for (int r = 0; r < kReaders; ++r) {
    readers.push_back(std::make_unique<haptel::test::Thread>("reader", [&, r] {
      ReaderResult& out = results[static_cast<size_t>(r)];
      started.fetch_add(1);
      uint64_t previous = 0;
      uint64_t previous_version = 0;
      // Keep reading until the writer is done, then once more.
      bool last_round = false;
      while (true) {
        last_round = done.load(std::memory_order_acquire);
        const uint64_t version = lock.Version();
        const Sample s = lock.Load();
        ++out.loads;
        if (!Consistent(s)) ++out.torn;
        if (s.ints[0] < previous) ++out.backwards;
        if (version < previous_version) ++out.version_backwards;
        if (s.ints[0] + base < version) ++out.older_than_version;
        previous = s.ints[0];
        previous_version = version;
        if (last_round) break;
      }
      out.last = previous;
    }));
  }
  // Let the readers get going so that stores and loads overlap (they stop
  // once the writer is done, started or not).
  const haptel::test::Deadline deadline(60.0);
  while (started.load() < kReaders && !deadline.passed()) std::this_thread::yield();
  CHECK(started.load() == kReaders);

  haptel::test::Thread writer("writer", [&] {
    for (uint64_t i = 1; i <= kStores; ++i) lock.Store(MakeSample(i));
    done.store(true, std::memory_order_release);
  });
  writer.Join();
  for (auto& t : readers) t->Join();

  for (const auto& r : results) {
    CHECK(r.loads > 0);
    CHECK(r.torn == 0);
    CHECK(r.backwards == 0);
    CHECK(r.version_backwards == 0);
    CHECK(r.older_than_version == 0);
    // The writer finished before the final read, so the reader saw the last value.
    CHECK(r.last == kStores);
  }
  CHECK(Consistent(lock.Load()));
  CHECK(lock.Load().ints[0] == kStores);
}

TEST_CASE("Seqlock: TryLoad gives up on a store held in progress and keeps the caller's value",
          "[seqlock]") {
  haptel::Seqlock<Sample> lock(MakeSample(3));
  Sample out = MakeSample(9);
  REQUIRE(lock.TryLoad(out, 1));
  CHECK(out.ints[0] == 3);

  // A writer pre-empted between its two sequence bumps.
  haptel::SeqlockTestAccess::BeginStore(lock);
  out = MakeSample(9);
  CHECK_FALSE(lock.TryLoad(out, 4));
  CHECK(out.ints[0] == 9);  // untouched: the caller's last good value
  CHECK(Consistent(out));

  haptel::SeqlockTestAccess::EndStore(lock);
  REQUIRE(lock.TryLoad(out, 1));
  CHECK(out.ints[0] == 3);
}
