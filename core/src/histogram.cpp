#include "haptel/core/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace haptel {

namespace {
// Validates before the bins are allocated: a negative count must not reach new[].
int CheckedBins(double bin_width_us, int bins) {
  if (!(bin_width_us > 0.0) || bins < 1) {
    throw std::invalid_argument("Histogram: bin width must be > 0 and bins >= 1");
  }
  return bins;
}
}  // namespace

Histogram::Histogram(double bin_width_us, int bins)
    : bin_width_us_(bin_width_us),
      bins_(CheckedBins(bin_width_us, bins)),
      counts_(new std::atomic<uint64_t>[static_cast<size_t>(bins_) + 1]) {
  Reset();
}

void Histogram::Record(double value_us) {
  if (!std::isfinite(value_us)) return;
  const double clamped = std::max(0.0, value_us);
  // Compare in double first: converting an index past INT_MAX to int is undefined.
  const double index = clamped / bin_width_us_;
  const int bin = index >= static_cast<double>(bins_) ? bins_ : static_cast<int>(index);
  counts_[bin].fetch_add(1, std::memory_order_relaxed);
  total_.fetch_add(1, std::memory_order_relaxed);
  // Single recorder per histogram, so a relaxed read-modify-write is enough.
  sum_us_.store(sum_us_.load(std::memory_order_relaxed) + clamped, std::memory_order_relaxed);
  if (clamped > max_us_.load(std::memory_order_relaxed)) {
    max_us_.store(clamped, std::memory_order_relaxed);
  }
}

void Histogram::Reset() {
  for (int i = 0; i <= bins_; ++i) counts_[i].store(0, std::memory_order_relaxed);
  total_.store(0);
  sum_us_.store(0.0);
  max_us_.store(0.0);
}

uint64_t Histogram::Count() const { return total_.load(std::memory_order_relaxed); }

uint64_t Histogram::BinCount(int i) const { return counts_[i].load(std::memory_order_relaxed); }

double Histogram::Percentile(double q) const {
  uint64_t total = 0;
  for (int i = 0; i <= bins_; ++i) total += BinCount(i);
  if (total == 0) return 0.0;
  const auto rank = static_cast<uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * total));
  uint64_t seen = 0;
  for (int i = 0; i < bins_; ++i) {
    seen += BinCount(i);
    if (seen >= std::max<uint64_t>(rank, 1)) return (i + 1) * bin_width_us_;
  }
  return MaxUs();
}

double Histogram::MaxUs() const { return max_us_.load(std::memory_order_relaxed); }

double Histogram::MeanUs() const {
  const uint64_t n = Count();
  return n == 0 ? 0.0 : sum_us_.load(std::memory_order_relaxed) / static_cast<double>(n);
}

}  // namespace haptel
