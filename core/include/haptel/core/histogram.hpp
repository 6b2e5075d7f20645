#pragma once
/// @file Fixed-bin histogram for loop periods and latencies.
///
/// Bins are atomics so one thread can record while others read percentiles;
/// recording never allocates (the bins are sized at construction).
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace haptel {

class Histogram {
 public:
  /// @param bin_width_us width of one bin, µs.
  /// @param bins number of bins; values past the last bin land in an overflow bin.
  Histogram(double bin_width_us, int bins);

  /// Records one value in µs. Wait-free, allocation-free.
  void Record(double value_us);
  void Reset();

  uint64_t Count() const;
  /// Value below which the fraction q (0..1) of samples fall, at bin resolution
  /// (the upper edge of the bin). Returns 0 with no samples.
  double Percentile(double q) const;
  double MaxUs() const;
  double MeanUs() const;
  double bin_width_us() const { return bin_width_us_; }
  int bins() const { return bins_; }
  /// Count in bin i (i == bins() is the overflow bin).
  uint64_t BinCount(int i) const;

 private:
  double bin_width_us_;
  int bins_;
  std::unique_ptr<std::atomic<uint64_t>[]> counts_;
  std::atomic<uint64_t> total_{0};
  std::atomic<double> sum_us_{0.0};
  std::atomic<double> max_us_{0.0};
};

}  // namespace haptel
