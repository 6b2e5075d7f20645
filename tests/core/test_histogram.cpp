// Histogram: fixed bins, overflow bin, percentiles at bin resolution.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "haptel/core/histogram.hpp"

using haptel::Histogram;

TEST_CASE("Histogram: an empty histogram reports zeros", "[histogram]") {
  Histogram h(10.0, 100);
  CHECK(h.Count() == 0);
  CHECK(h.Percentile(0.5) == 0.0);
  CHECK(h.MaxUs() == 0.0);
  CHECK(h.MeanUs() == 0.0);
  CHECK(h.bin_width_us() == 10.0);
  CHECK(h.bins() == 100);
  for (int i = 0; i <= h.bins(); ++i) CHECK(h.BinCount(i) == 0);
}

TEST_CASE("Histogram: percentiles of 1..1000 us are within one bin", "[histogram]") {
  const double width = 10.0;
  Histogram h(width, 200);
  double sum = 0.0;
  for (int v = 1; v <= 1000; ++v) {
    h.Record(v);
    sum += v;
  }
  REQUIRE(h.Count() == 1000);
  // The exact percentile of 1..1000 at q is q*1000.
  CHECK(std::abs(h.Percentile(0.50) - 500.0) <= width);
  CHECK(std::abs(h.Percentile(0.90) - 900.0) <= width);
  CHECK(std::abs(h.Percentile(0.99) - 990.0) <= width);
  // At bin resolution the result is a bin's upper edge, never below the true value.
  CHECK(h.Percentile(0.50) >= 500.0);
  CHECK(h.Percentile(0.99) >= 990.0);
  CHECK(h.Percentile(1.0) >= 1000.0);
  CHECK(h.Percentile(0.0) <= width);
  // Percentiles do not decrease with q.
  double previous = 0.0;
  for (double q = 0.0; q <= 1.0; q += 0.05) {
    const double p = h.Percentile(q);
    CHECK(p >= previous);
    previous = p;
  }
  CHECK(h.MaxUs() == 1000.0);
  CHECK(h.MeanUs() == Approx(sum / 1000.0));
  // Nothing past 2000 us, so the overflow bin is empty.
  CHECK(h.BinCount(h.bins()) == 0);
}

TEST_CASE("Histogram: values land in the bin their value selects", "[histogram]") {
  Histogram h(5.0, 10);
  h.Record(0.0);   // bin 0
  h.Record(4.9);   // bin 0
  h.Record(5.0);   // bin 1 (lower edge belongs to the bin)
  h.Record(12.0);  // bin 2
  h.Record(49.9);  // bin 9, the last regular bin
  CHECK(h.BinCount(0) == 2);
  CHECK(h.BinCount(1) == 1);
  CHECK(h.BinCount(2) == 1);
  CHECK(h.BinCount(9) == 1);
  CHECK(h.BinCount(10) == 0);
  CHECK(h.Count() == 5);
}

TEST_CASE("Histogram: values past the last bin go to the overflow bin", "[histogram]") {
  const double width = 10.0;
  const int bins = 50;  // covers [0, 500) us
  Histogram h(width, bins);
  for (int i = 0; i < 90; ++i) h.Record(100.0);
  for (int i = 0; i < 10; ++i) h.Record(5000.0 + i);
  h.Record(500.0);  // exactly the end of the range: overflow too
  CHECK(h.Count() == 101);
  CHECK(h.BinCount(bins) == 11);
  CHECK(h.BinCount(10) == 90);
  CHECK(h.MaxUs() == 5009.0);
  // A percentile that falls in the overflow bin reports the maximum seen.
  CHECK(h.Percentile(0.99) == h.MaxUs());
  // One that falls in a regular bin does not.
  CHECK(std::abs(h.Percentile(0.5) - 100.0) <= width);
}

TEST_CASE("Histogram: very large values land in the overflow bin", "[histogram]") {
  Histogram h(10.0, 100);
  h.Record(1e12);  // about eleven days, far past the int range of bin indices
  h.Record(1e300);
  h.Record(std::numeric_limits<double>::max());
  CHECK(h.Count() == 3);
  CHECK(h.BinCount(h.bins()) == 3);
  for (int i = 0; i < h.bins(); ++i) CHECK(h.BinCount(i) == 0);
  CHECK(h.MaxUs() == std::numeric_limits<double>::max());
}

TEST_CASE("Histogram: negative values count as zero", "[histogram]") {
  Histogram h(10.0, 10);
  h.Record(-5.0);
  CHECK(h.Count() == 1);
  CHECK(h.BinCount(0) == 1);
  CHECK(h.MeanUs() == 0.0);
}

TEST_CASE("Histogram: max and mean", "[histogram]") {
  Histogram h(1.0, 1000);
  h.Record(10.0);
  h.Record(30.0);
  h.Record(20.0);
  CHECK(h.MaxUs() == 30.0);
  CHECK(h.MeanUs() == Approx((10.0 + 30.0 + 20.0) / 3.0));
}

TEST_CASE("Histogram: NaN and infinities are ignored", "[histogram]") {
  Histogram h(10.0, 10);
  h.Record(20.0);
  h.Record(std::numeric_limits<double>::quiet_NaN());
  h.Record(std::numeric_limits<double>::infinity());
  h.Record(-std::numeric_limits<double>::infinity());
  CHECK(h.Count() == 1);
  CHECK(h.MaxUs() == 20.0);
  CHECK(h.MeanUs() == 20.0);
  CHECK(h.BinCount(h.bins()) == 0);
  CHECK(std::isfinite(h.Percentile(0.5)));
}

TEST_CASE("Histogram: Reset clears counts, max and mean", "[histogram]") {
  Histogram h(10.0, 10);
  for (int i = 0; i < 20; ++i) h.Record(i * 7.0);
  h.Record(1e6);
  REQUIRE(h.Count() == 21);
  h.Reset();
  CHECK(h.Count() == 0);
  CHECK(h.MaxUs() == 0.0);
  CHECK(h.MeanUs() == 0.0);
  CHECK(h.Percentile(0.5) == 0.0);
  for (int i = 0; i <= h.bins(); ++i) CHECK(h.BinCount(i) == 0);
  // It records normally afterwards.
  h.Record(35.0);
  CHECK(h.Count() == 1);
  CHECK(h.BinCount(3) == 1);
  CHECK(h.MaxUs() == 35.0);
}

TEST_CASE("Histogram: invalid constructor arguments throw", "[histogram]") {
  CHECK_THROWS_AS(Histogram(0.0, 10), std::invalid_argument);
  CHECK_THROWS_AS(Histogram(-1.0, 10), std::invalid_argument);
  CHECK_THROWS_AS(Histogram(std::numeric_limits<double>::quiet_NaN(), 10), std::invalid_argument);
  CHECK_THROWS_AS(Histogram(10.0, 0), std::invalid_argument);
  CHECK_THROWS_AS(Histogram(10.0, -1), std::invalid_argument);
  CHECK_THROWS_AS(Histogram(10.0, -5), std::invalid_argument);
  CHECK_NOTHROW(Histogram(0.5, 1));
}
