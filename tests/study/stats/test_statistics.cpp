// The study's statistics against values computed independently of this code:
// SciPy 1.10.1 (Debian 12's python3-scipy) for everything SciPy has, and the
// arithmetic written out below for what it has not (Kendall's W, Nemenyi's
// critical difference, Holm). Re-run the Python with /usr/bin/python3 -W ignore
// (the warnings are SciPy's "sample size too small for normal approximation").
//
// clang-format off
//   import numpy as np
//   from scipy import stats, special
//
//   def friedman(rows):
//       cols = list(zip(*rows))
//       r = stats.friedmanchisquare(*cols)
//       ranks = np.array([stats.rankdata(row) for row in rows])
//       return r.statistic, r.pvalue, ranks.sum(axis=0), ranks.mean(axis=0)
//
//   def kendall_w(rows):  # tie-corrected, from the definition (no SciPy function)
//       ranks = np.array([stats.rankdata(row) for row in rows])
//       m, k = ranks.shape
//       s = ((ranks.sum(axis=0) - m * (k + 1) / 2) ** 2).sum()
//       t = sum((c ** 3 - c).sum() for c in
//               (np.unique(row, return_counts=True)[1] for row in rows))
//       return 12 * s / (m * m * (k ** 3 - k) - m * t)
//
//   no_ties = [[12.1, 14.3, 11.0, 15.2], [10.5, 13.9, 12.2, 16.0], [11.8, 12.7, 10.9, 14.1],
//              [13.0, 15.5, 12.4, 14.8], [9.9, 11.2, 12.0, 13.3]]
//   with_ties = [[20, 20, 25, 30], [18, 22, 22, 22], [15, 19, 17, 19],
//                [30, 28, 28, 35], [24, 24, 24, 26], [21, 23, 20, 25]]
//   thesis = [[210, 225, 170, 120], [600, 600, 150, 120], [245, 220, 190, 110],
//             [320, 405, 325, 210], [310, 240, 220, 200]]
//   for name, rows in [("no_ties", no_ties), ("with_ties", with_ties), ("thesis", thesis)]:
//       chi2, p, sums, means = friedman(rows)
//       print(name, "chi2=%.17g p=%.17g W=%.17g" % (chi2, p, kendall_w(rows)),
//             "sums", list(sums), "means", list(means))
//
//   def wil(x, y, method):
//       r = stats.wilcoxon(x, y, zero_method="wilcox", correction=False,
//                          alternative="two-sided", method=method)
//       return "T=%.17g p=%.17g" % (r.statistic, r.pvalue)
//
//   x9 = [1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30]
//   y9 = [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29]
//   print("exact9", wil(x9, y9, "exact"))
//   xz = [10, 12, 14, 15, 9, 11, 13, 16, 12, 10, 17, 14]
//   yz = [10, 11, 12, 15, 11, 9, 13, 13, 10, 12, 14, 12]
//   print("ties_zeros", wil(xz, yz, "approx"))
//   xt = [5.0, 7.0, 6.0, 9.0, 4.0, 8.0, 6.5]
//   yt = [4.0, 5.0, 7.0, 6.0, 3.0, 6.0, 8.5]
//   print("ties_only", wil(xt, yt, "approx"))
//   y30 = [float(i) for i in range(30)]
//   x30 = [i + 0.25 * (i + 1) * (-1 if i % 4 == 0 else 1) for i in range(30)]
//   d30 = np.subtract(x30, y30)
//   assert len(set(np.abs(d30))) == 30 and np.all(d30 != 0)
//   print("n30", wil(x30, y30, "approx"))
//   print("n25_exact", wil(x30[:25], y30[:25], "exact"))
//   print("thesis simple-gesture", wil([210, 600, 245, 320, 310], [120, 120, 110, 210, 200], "approx"))
//   print("thesis simple-hud", wil([210, 600, 245, 320, 310], [225, 600, 220, 405, 240], "approx"))
//
//   for a, x in [(0.5, 0.1), (1.0, 1.0), (3.0, 2.5), (10.0, 3.0), (10.0, 20.0), (2.5, 50.0),
//                (0.1, 5.0), (100.0, 90.0), (1.5, 2.0), (7.5, 8.5)]:
//       print("Q(%g, %g) = %.17g" % (a, x, special.gammaincc(a, x)))
//   for x, df in [(3.841458820694124, 1), (12.183673469387756, 3), (0.5, 2), (30.0, 9),
//                 (1e-3, 4), (80.0, 3)]:
//       print("chi2.sf(%.17g, %d) = %.17g" % (x, df, stats.chi2.sf(x, df)))
//
//   k3 = [[3, 1, 2], [2, 2, 1], [1, 3, 2], [3, 2, 1], [2, 1, 3], [3, 1, 2], [2, 3, 1], [3, 1, 1],
//         [1, 2, 3], [3, 2, 1]]
//   chi2, p, sums, means = friedman(k3)
//   print("k3 chi2=%.17g p=%.17g W=%.17g" % (chi2, p, kendall_w(k3)), list(sums))
//
//   # Pairwise Wilcoxon with Haptel's rule (exact when n <= 25 without ties or
//   # zeros, else the normal approximation) and Holm's step-down adjustment written
//   # out from its definition (SciPy 1.10 has no Holm).
//   cols = list(zip(*thesis))
//   pairs = [(a, b) for a in range(4) for b in range(a + 1, 4)]
//   ps = []
//   for a, b in pairs:
//       d = np.subtract(cols[a], cols[b])
//       exact = len(d) <= 25 and np.all(d != 0) and len(set(np.abs(d))) == len(d)
//       r = stats.wilcoxon(cols[a], cols[b], correction=False,
//                          method="exact" if exact else "approx")
//       ps.append(r.pvalue)
//       print("pair", a, b, "exact" if exact else "approx", "T=%.17g p=%.17g" % (r.statistic, r.pvalue))
//   order = sorted(range(len(ps)), key=lambda i: ps[i])
//   adj, running = [0.0] * len(ps), 0.0
//   for rank, i in enumerate(order):
//       running = max(running, min(1.0, (len(ps) - rank) * ps[i]))
//       adj[i] = running
//   print("holm", ["%.17g" % v for v in adj])
//
// Its output:
//   no_ties chi2=10.679999999999993 p=0.0135882729582177 W=0.71199999999999997 sums [8.0, 15.0, 8.0, 19.0] means [1.6, 3.0, 1.6, 3.8]
//   with_ties chi2=10.163265306122463 p=0.017228104492999986 W=0.56462585034013602 sums [10.5, 14.5, 12.5, 22.5] means [1.75, 2.4166666666666665, 2.0833333333333335, 3.75]
//   thesis chi2=12.183673469387752 p=0.0067797401305199397 W=0.81224489795918364 sums [16.5, 17.5, 11.0, 5.0] means [3.3, 3.5, 2.2, 1.0]
//   exact9 T=5 p=0.0390625
//   ties_zeros T=9 p=0.098458502377584176
//   ties_only T=7 p=0.22994905679421362
//   n30 T=120 p=0.02067111356691231
//   n25_exact T=91 p=0.055070459842681885
//   thesis simple-gesture T=0 p=0.042168197097155961
//   thesis simple-hud T=5 p=1
//   Q(0.5, 0.1) = 0.65472084601857683
//   Q(1, 1) = 0.36787944117144245
//   Q(3, 2.5) = 0.5438131158833297
//   Q(10, 3) = 0.99889751186988451
//   Q(10, 20) = 0.0049954123083075785
//   Q(2.5, 50) = 5.2851483609432189e-20
//   Q(0.1, 5) = 0.00014393896584673387
//   Q(100, 90) = 0.84177901081356998
//   Q(1.5, 2) = 0.26146412994911117
//   Q(7.5, 8.5) = 0.31886440545231459
//   chi2.sf(3.841458820694124, 1) = 0.049999999999999892
//   chi2.sf(12.183673469387756, 3) = 0.0067797401305199258
//   chi2.sf(0.5, 2) = 0.77880078307140488
//   chi2.sf(30, 9) = 0.00043872177097947936
//   chi2.sf(0.001, 4) = 0.99999987504165888
//   chi2.sf(80, 3) = 3.0692774861724164e-17
//   k3 chi2=2.0526315789473717 p=0.35832467524990291 W=0.10263157894736842 [23.5, 19.0, 17.5]
//   pair 0 1 approx T=5 p=1
//   pair 0 2 exact T=1 p=0.125
//   pair 0 3 approx T=0 p=0.042168197097155961
//   pair 1 2 exact T=0 p=0.0625
//   pair 1 3 exact T=0 p=0.0625
//   pair 2 3 exact T=0 p=0.0625
//   holm ['1', '0.3125', '0.25300918258293575', '0.3125', '0.3125', '0.3125']
// clang-format on
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/study/statistics.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;
using haptel::study::BlockMatrix;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// SciPy and this code add the same numbers in another order.
Approx Close(double expected) { return Approx(expected).epsilon(1e-12).margin(0.0); }

template <typename F>
std::string InvalidArgument(F&& f) {
  return haptel::test::WhatOf<std::invalid_argument>(std::forward<F>(f));
}

// Rows: participants; columns: conditions. The script's matrices, as given there.
const BlockMatrix kNoTies = {{12.1, 14.3, 11.0, 15.2},
                             {10.5, 13.9, 12.2, 16.0},
                             {11.8, 12.7, 10.9, 14.1},
                             {13.0, 15.5, 12.4, 14.8},
                             {9.9, 11.2, 12.0, 13.3}};
const BlockMatrix kWithTies = {{20, 20, 25, 30}, {18, 22, 22, 22}, {15, 19, 17, 19},
                               {30, 28, 28, 35}, {24, 24, 24, 26}, {21, 23, 20, 25}};
// The thesis: participants A-E; simple cockpit, cockpit + HUD, assisted,
// gesture; lap times in s.
const BlockMatrix kThesis = {{210, 225, 170, 120},
                             {600, 600, 150, 120},
                             {245, 220, 190, 110},
                             {320, 405, 325, 210},
                             {310, 240, 220, 200}};

std::vector<double> Column(const BlockMatrix& m, int j) {
  std::vector<double> out;
  for (const auto& row : m) out.push_back(row[j]);
  return out;
}

void CheckRanks(const haptel::study::FriedmanResult& r, const std::vector<double>& sums) {
  REQUIRE(r.ranks.size() == sums.size());
  for (std::size_t j = 0; j < sums.size(); ++j) {
    CHECK(r.ranks[j].rank_sum == Close(sums[j]));
    CHECK(r.ranks[j].mean_rank == Close(sums[j] / r.participants));
  }
}

}  // namespace

TEST_CASE("Ranks: 1 for the smallest, ties share their average rank", "[study][stats]") {
  using haptel::study::Ranks;
  // 1 and 1 take ranks 1 and 2: both 1.5 (scipy.stats.rankdata gives the same).
  CHECK(Ranks({3, 1, 4, 1, 5}) == std::vector<double>{3, 1.5, 4, 1.5, 5});
  CHECK(Ranks({2, 2, 2}) == std::vector<double>{2, 2, 2});
  CHECK(Ranks({-0.5, 10, 7}) == std::vector<double>{1, 3, 2});
  CHECK(Ranks({42}) == std::vector<double>{1});
  CHECK(Ranks({}).empty());
  // Three tied in the middle: ranks 2, 3, 4 -> 3 each; the sum stays n(n+1)/2.
  CHECK(Ranks({9, 5, 5, 1, 5}) == std::vector<double>{5, 3, 3, 1, 3});
}

TEST_CASE("RegularizedUpperGamma: SciPy's special.gammaincc and closed forms", "[study][stats]") {
  using haptel::study::RegularizedUpperGamma;
  // The series branch (x < a + 1) and the continued fraction (x >= a + 1).
  CHECK(RegularizedUpperGamma(0.5, 0.1) == Close(0.65472084601857683));
  CHECK(RegularizedUpperGamma(1.0, 1.0) == Close(0.36787944117144245));
  CHECK(RegularizedUpperGamma(3.0, 2.5) == Close(0.5438131158833297));
  CHECK(RegularizedUpperGamma(10.0, 3.0) == Close(0.99889751186988451));
  CHECK(RegularizedUpperGamma(10.0, 20.0) == Close(0.0049954123083075785));
  CHECK(RegularizedUpperGamma(2.5, 50.0) == Close(5.2851483609432189e-20));
  CHECK(RegularizedUpperGamma(0.1, 5.0) == Close(0.00014393896584673387));
  CHECK(RegularizedUpperGamma(1.5, 2.0) == Close(0.26146412994911117));
  CHECK(RegularizedUpperGamma(7.5, 8.5) == Close(0.31886440545231459));
  // a = 100: x^a e^-x / Gamma(a) is a difference of terms near 450 in the log.
  CHECK(RegularizedUpperGamma(100.0, 90.0) == Approx(0.84177901081356998).epsilon(1e-11));
  // Q(1, x) = e^-x and Q(1/2, x) = erfc(sqrt(x)), on both sides of x = a + 1.
  for (double x : {0.01, 0.7, 1.4, 3.0, 12.0, 40.0}) {
    CHECK(RegularizedUpperGamma(1.0, x) == Close(std::exp(-x)));
    CHECK(RegularizedUpperGamma(0.5, x) == Close(std::erfc(std::sqrt(x))));
  }
  CHECK(RegularizedUpperGamma(2.0, 0.0) == 1.0);
}

TEST_CASE("ChiSquareSurvival: SciPy's chi2.sf", "[study][stats]") {
  using haptel::study::ChiSquareSurvival;
  CHECK(ChiSquareSurvival(3.841458820694124, 1) == Close(0.049999999999999892));
  CHECK(ChiSquareSurvival(12.183673469387756, 3) == Close(0.0067797401305199258));
  CHECK(ChiSquareSurvival(0.5, 2) == Close(0.77880078307140488));
  CHECK(ChiSquareSurvival(30.0, 9) == Close(0.00043872177097947936));
  CHECK(ChiSquareSurvival(1e-3, 4) == Close(0.99999987504165888));
  CHECK(ChiSquareSurvival(80.0, 3) == Close(3.0692774861724164e-17));
  CHECK(ChiSquareSurvival(0.0, 5) == 1.0);
}

TEST_CASE("FriedmanTest: 5 participants x 4 conditions without ties", "[study][stats]") {
  const auto r = haptel::study::FriedmanTest(kNoTies);
  CHECK(r.participants == 5);
  CHECK(r.conditions == 4);
  CHECK(r.degrees_of_freedom == 3);
  CheckRanks(r, {8, 15, 8, 19});
  CHECK(r.chi_square == Close(10.679999999999993));
  CHECK(r.p_value_asymptotic == Close(0.0135882729582177));
  // By hand: S = (8-12.5)^2 + (15-12.5)^2 + (8-12.5)^2 + (19-12.5)^2
  //            = 20.25 + 6.25 + 20.25 + 42.25 = 89; no ties, so
  // W = 12 S / (N^2 (k^3 - k)) = 1068 / (25 * 60) = 0.712.
  CHECK(r.kendall_w == Close(0.712));
  CHECK(haptel::study::KendallW(kNoTies) == Close(0.712));
}

TEST_CASE("FriedmanTest: ties within rows take SciPy's tie correction", "[study][stats]") {
  const auto r = haptel::study::FriedmanTest(kWithTies);
  CHECK(r.participants == 6);
  CHECK(r.conditions == 4);
  CheckRanks(r, {10.5, 14.5, 12.5, 22.5});
  CHECK(r.chi_square == Close(10.163265306122463));
  CHECK(r.p_value_asymptotic == Close(0.017228104492999986));
  CHECK(r.kendall_w == Close(0.56462585034013602));
  CHECK(r.kendall_w == Close(r.chi_square / (r.participants * (r.conditions - 1))));
}

TEST_CASE("FriedmanTest: 10 participants x 3 conditions, many ties", "[study][stats]") {
  const BlockMatrix k3 = {{3, 1, 2}, {2, 2, 1}, {1, 3, 2}, {3, 2, 1}, {2, 1, 3},
                          {3, 1, 2}, {2, 3, 1}, {3, 1, 1}, {1, 2, 3}, {3, 2, 1}};
  const auto r = haptel::study::FriedmanTest(k3);
  CheckRanks(r, {23.5, 19.0, 17.5});
  CHECK(r.degrees_of_freedom == 2);
  CHECK(r.chi_square == Close(2.0526315789473717));
  CHECK(r.p_value_asymptotic == Close(0.35832467524990291));
  CHECK(r.kendall_w == Close(0.10263157894736842));
}

TEST_CASE("FriedmanTest: the thesis's lap times", "[study][stats]") {
  const auto r = haptel::study::FriedmanTest(kThesis);
  CHECK(r.participants == 5);
  CHECK(r.conditions == 4);
  // Ranks per participant (1 = fastest):
  //   A 210 225 170 120 -> 3   4   2 1
  //   B 600 600 150 120 -> 3.5 3.5 2 1   (the two 600 s share ranks 3 and 4)
  //   C 245 220 190 110 -> 4   3   2 1
  //   D 320 405 325 210 -> 2   4   3 1
  //   E 310 240 220 200 -> 4   3   2 1
  // Rank sums 16.5 17.5 11 5 (total 50 = N k (k+1) / 2), mean ranks 3.3 3.5 2.2 1.0.
  CheckRanks(r, {16.5, 17.5, 11.0, 5.0});
  CHECK(r.chi_square == Close(12.183673469387752));
  CHECK(r.p_value_asymptotic == Close(0.0067797401305199397));
  // Kendall's W by hand: N (k+1) / 2 = 12.5;
  //   S = 4^2 + 5^2 + (-1.5)^2 + (-7.5)^2 = 16 + 25 + 2.25 + 56.25 = 99.5;
  //   T = 2^3 - 2 = 6 (participant B's one pair of ties);
  //   W = 12 S / (N^2 (k^3 - k) - N T) = 1194 / (25 * 60 - 5 * 6) = 1194 / 1470
  //     = 0.812244897959...; and chi2 = W N (k - 1) = 15 W = 12.1836734693...
  CHECK(r.kendall_w == Close(1194.0 / 1470.0));
  CHECK(r.chi_square == Close(15.0 * 1194.0 / 1470.0));
}

TEST_CASE("FriedmanTest: 2 conditions, where it is the sign test's chi-square", "[study][stats]") {
  // SciPy refuses k = 2. By hand: ranks (1,2), (1,2), (2,1): sums 4 and 5,
  // S = 0.25 + 0.25 = 0.5, chi2 = 12 S (k-1) / (N (k^3 - k)) = 6 / 18 = 1/3,
  // which is the sign test's (n+ - n-)^2 / n = (2 - 1)^2 / 3; with 1 degree of
  // freedom p = Q(1/2, chi2/2) = erfc(sqrt(1/6)) = 0.563702861650773.
  const auto r = haptel::study::FriedmanTest({{1, 2}, {1, 2}, {2, 1}});
  CHECK(r.degrees_of_freedom == 1);
  CHECK(r.chi_square == Close(1.0 / 3.0));
  CHECK(r.p_value_asymptotic == Close(0.563702861650773));
  CHECK(r.kendall_w == Close(1.0 / 9.0));  // chi2 / (N (k - 1)) = (1/3) / 3
  // Exact: a 2-1 split is the least extreme there is with 3 participants.
  CHECK(r.p_exact);
  CHECK(r.p_value == Close(1.0));
}

namespace {

/// The exact p of Friedman's test by brute force, independently of the
/// dynamic programme: every one of the k! orderings of every row's ranks
/// (tied ranks permuted as if distinct, so each of the (k!)^N combinations
/// is equally likely), counting those whose S is at least the observed one.
/// S is compared in doubled ranks, where it is an integer.
double BruteForceFriedmanP(const BlockMatrix& values) {
  const std::size_t k = values.front().size();
  std::vector<std::vector<long>> rows;
  std::vector<long> observed_sums(k, 0);
  for (const auto& row : values) {
    std::vector<long> doubled;
    for (double r : haptel::study::Ranks(row)) doubled.push_back(std::lround(2 * r));
    for (std::size_t j = 0; j < k; ++j) observed_sums[j] += doubled[j];
    rows.push_back(doubled);
  }
  const long doubled_mean = static_cast<long>(values.size() * (k + 1));
  const auto spread = [&](const std::vector<long>& sums) {
    long s = 0;
    for (long v : sums) s += (v - doubled_mean) * (v - doubled_mean);
    return s;
  };
  const long observed = spread(observed_sums);
  double total = 0;
  double at_least = 0;
  std::vector<long> sums(k, 0);
  std::function<void(std::size_t)> visit = [&](std::size_t row) {
    if (row == rows.size()) {
      total += 1;
      if (spread(sums) >= observed) at_least += 1;
      return;
    }
    std::vector<std::size_t> order(k);
    std::iota(order.begin(), order.end(), std::size_t{0});
    do {
      for (std::size_t j = 0; j < k; ++j) sums[j] += rows[row][order[j]];
      visit(row + 1);
      for (std::size_t j = 0; j < k; ++j) sums[j] -= rows[row][order[j]];
    } while (std::next_permutation(order.begin(), order.end()));
  };
  visit(0);
  return at_least / total;
}

}  // namespace

// Published tables of Friedman's exact distribution (e.g. Hollander & Wolfe,
// Nonparametric Statistical Methods; Siegel & Castellan, Table M) give
// P(χ²_F ≥ x) to 3 decimals; the brute force above gives the fraction.
TEST_CASE("FriedmanTest: exact p as the published tables, k = 3, N = 3", "[study][stats]") {
  // Perfect concordance: rank sums 3, 6, 9, S = 18, χ²_F = 12·18/36 = 6.0.
  // Only the 6 of 216 combinations where all three rows agree reach it: 1/36.
  const BlockMatrix concordant = {{1, 2, 3}, {1, 2, 3}, {1, 2, 3}};
  const auto r = haptel::study::FriedmanTest(concordant);
  CHECK(r.chi_square == Close(6.0));
  CHECK(r.p_exact);
  CHECK(r.p_value == Close(1.0 / 36.0));  // table: .028
  CHECK(r.p_value == Close(BruteForceFriedmanP(concordant)));
  CHECK(r.p_value_asymptotic == Close(std::exp(-3.0)));  // χ² with 2 df: e^(−x/2) = 0.0498
  // Rank sums 4, 5, 9: S = 4 + 1 + 9 = 14, χ²_F = 12·14/36 = 4.667; 42 of 216.
  const BlockMatrix one_swap = {{1, 2, 3}, {1, 2, 3}, {2, 1, 3}};
  const auto s = haptel::study::FriedmanTest(one_swap);
  CHECK(s.chi_square == Close(14.0 / 3.0));
  CHECK(s.p_exact);
  CHECK(s.p_value == Close(7.0 / 36.0));  // table: .194
  CHECK(s.p_value == Close(BruteForceFriedmanP(one_swap)));
}

TEST_CASE("FriedmanTest: exact p as the published tables, k = 4, N = 2", "[study][stats]") {
  // Rank sums 2, 4, 6, 8: S = 9 + 1 + 1 + 9 = 20, χ²_F = 12·20/40 = 6.0, the
  // largest there is: the second row equals the first, 24 of 576.
  const BlockMatrix concordant = {{1, 2, 3, 4}, {10, 20, 30, 40}};
  const auto r = haptel::study::FriedmanTest(concordant);
  CHECK(r.chi_square == Close(6.0));
  CHECK(r.p_exact);
  CHECK(r.p_value == Close(1.0 / 24.0));  // table: .042
  CHECK(r.p_value == Close(BruteForceFriedmanP(concordant)));
}

TEST_CASE("FriedmanTest: exact p as the published tables, k = 4, N = 4 (docs/studies.md)",
          "[study][stats]") {
  // The synthetic study's two reports in docs/studies.md, by their rank sums
  // (gesture, assisted, cockpit-hud, cockpit; no ties). Mean ranks 1, 2, 3.5,
  // 3.5: sums 4, 8, 14, 14, S = 36 + 4 + 16 + 16 = 72, χ²_F = 12·72/80 = 10.8.
  const BlockMatrix full = {{1, 2, 3, 4}, {1, 2, 3, 4}, {1, 2, 4, 3}, {1, 2, 4, 3}};
  const auto r = haptel::study::FriedmanTest(full);
  CHECK(r.chi_square == Close(10.8));
  CHECK(r.p_exact);
  CHECK(r.p_value == Approx(0.0016).margin(0.00005));  // table: .0016
  CHECK(r.p_value == Close(BruteForceFriedmanP(full)));
  // Mean ranks 1, 2.5, 3.25, 3.25: sums 4, 10, 13, 13, S = 54, χ²_F = 8.1.
  const BlockMatrix simulated = {{1, 2, 3, 4}, {1, 3, 2, 4}, {1, 3, 4, 2}, {1, 2, 4, 3}};
  const auto s = haptel::study::FriedmanTest(simulated);
  CHECK(s.chi_square == Close(8.1));
  CHECK(s.p_exact);
  CHECK(s.p_value == Approx(0.033).margin(0.0005));  // table: .033
  CHECK(s.p_value == Close(BruteForceFriedmanP(simulated)));
  CHECK(s.p_value_asymptotic == Approx(0.044).margin(0.0005));
}

TEST_CASE("FriedmanTest: 2 conditions, 4 participants all one way: the sign test's p",
          "[study][stats]") {
  // χ²_F = 4 gives the χ² p 0.0455, below 0.05; the exact test is the
  // two-sided sign test: 2 of the 16 sign patterns are as extreme, p = 0.125.
  const BlockMatrix all_prefer_a = {{10, 12}, {9, 15}, {20, 21}, {11, 30}};
  const auto r = haptel::study::FriedmanTest(all_prefer_a);
  CHECK(r.chi_square == Close(4.0));
  CHECK(r.p_value_asymptotic == Close(std::erfc(std::sqrt(2.0))));  // 0.0455
  CHECK(r.p_exact);
  CHECK(r.p_value == Close(0.125));
  CHECK(r.p_value == Close(BruteForceFriedmanP(all_prefer_a)));
}

TEST_CASE("FriedmanTest: exact p with ties permutes each row's own midranks", "[study][stats]") {
  // Rows with a tied pair, a triple tie (no information), and untied rows.
  const BlockMatrix tied = {{5, 5, 7}, {1, 2, 3}, {4, 4, 4}, {3, 1, 1}, {2, 9, 6}};
  const auto r = haptel::study::FriedmanTest(tied);
  CHECK(r.p_exact);
  const double brute = BruteForceFriedmanP(tied);
  CHECK(r.p_value == Close(brute));
  CHECK(r.p_value != Close(r.p_value_asymptotic));
  // The thesis has one tied pair (participant B) and 4 conditions: 24^5 combinations.
  const auto thesis = haptel::study::FriedmanTest(kThesis);
  CHECK(thesis.p_exact);
  CHECK(thesis.p_value == Close(BruteForceFriedmanP(kThesis)));
  CHECK(thesis.p_value == Close(9168.0 / 7962624.0));  // 0.00115
  // The participants' order changes nothing, to the bit (the null
  // distribution is computed over the rows sorted, and remembered).
  const BlockMatrix reversed(tied.rbegin(), tied.rend());
  CHECK(haptel::study::FriedmanTest(reversed).p_value == r.p_value);
  CHECK(haptel::study::FriedmanExactP(reversed, 1000000) == r.p_value);
}

TEST_CASE("FriedmanTest: past the exact p's limits the chi-square p is kept", "[study][stats]") {
  using haptel::study::FriedmanExactP;
  // 7 conditions: more than kFriedmanExactMaxConditions.
  const BlockMatrix seven = {{1, 2, 3, 4, 5, 6, 7}, {2, 1, 3, 5, 4, 7, 6}, {7, 6, 5, 4, 3, 2, 1}};
  const auto r = haptel::study::FriedmanTest(seven);
  CHECK_FALSE(r.p_exact);
  CHECK(r.p_value == r.p_value_asymptotic);
  CHECK_FALSE(FriedmanExactP(seven).has_value());
  // 4 conditions, 40 participants: thousands of rank-sum vectors times 24
  // orderings a row, past kFriedmanExactMaxSteps.
  BlockMatrix many;
  for (int i = 0; i < 40; ++i)
    many.push_back({double(i % 4), double((i + 1) % 4), double((i * 3 + 2) % 4), 3.5});
  const auto m = haptel::study::FriedmanTest(many);
  CHECK_FALSE(m.p_exact);
  CHECK(m.p_value == m.p_value_asymptotic);
  // The step limit itself: the k = 3, N = 3 table case takes at most
  // 6 + 6 + 6·6 steps (states × a row's 6 orderings); 5 gives up, 1000 does not.
  const BlockMatrix concordant = {{1, 2, 3}, {1, 2, 3}, {1, 2, 3}};
  CHECK_FALSE(FriedmanExactP(concordant, 5).has_value());
  REQUIRE(FriedmanExactP(concordant, 1000).has_value());
  CHECK(*FriedmanExactP(concordant, 1000) == Close(1.0 / 36.0));
}

TEST_CASE("FriedmanTest: refuses what it cannot test, saying what it expected", "[study][stats]") {
  using haptel::study::FriedmanTest;
  CHECK_THAT(InvalidArgument([] { FriedmanTest({}); }),
             Contains("expected at least 2 participants (rows), got 0"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{1, 2, 3}});
             }),
             Contains("expected at least 2 participants (rows), got 1"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{1}, {2}});
             }),
             Contains("expected at least 2 conditions (columns), got 1"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{1, 2, 3, 4}, {1, 2, 3, 4}, {1, 2, 3}});
             }),
             Contains("expected every row to have 4 values (as row 0 has), row 2 has 3"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{1, 2}, {kNaN, 2}});
             }),
             Contains("row 1: expected finite values, got nan at index 0"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{1, kInf}, {1, 2}});
             }),
             Contains("row 0: expected finite values, got inf at index 1"));
  CHECK_THAT(InvalidArgument([] {
               FriedmanTest({{3, 3, 3}, {5, 5, 5}});
             }),
             Contains("every participant has the same value for all 3 conditions"));
  CHECK_THAT(InvalidArgument([] {
               haptel::study::KendallW({{1, 2, 3}});
             }),
             Contains("expected at least 2 participants"));
  // One untied row is enough to rank.
  CHECK(FriedmanTest({{3, 3, 3}, {1, 2, 3}}).chi_square > 0.0);
}

TEST_CASE("Nemenyi: Demsar's q_alpha and the critical difference", "[study][stats]") {
  using haptel::study::NemenyiCriticalDifference;
  using haptel::study::NemenyiCriticalValue;
  CHECK(NemenyiCriticalValue(2, 0.05) == 1.960);
  CHECK(NemenyiCriticalValue(4, 0.05) == 2.569);
  CHECK(NemenyiCriticalValue(10, 0.05) == 3.164);
  CHECK(NemenyiCriticalValue(2, 0.10) == 1.645);
  CHECK(NemenyiCriticalValue(4, 0.10) == 2.291);
  CHECK(NemenyiCriticalValue(10, 0.10) == 2.920);
  CHECK(NemenyiCriticalValue(7, 0.1) == 2.693);
  // CD = q sqrt(k (k+1) / (6 N)); k = 4, N = 5: sqrt(20 / 30) = 0.816496580927726,
  // so CD = 2.569 * 0.8164965809 = 2.0975797164 (alpha 0.05) and
  //    CD = 2.291 * 0.8164965809 = 1.8705936669 (alpha 0.10).
  CHECK(NemenyiCriticalDifference(4, 5, 0.05) == Close(2.0975797164033283));
  CHECK(NemenyiCriticalDifference(4, 5, 0.10) == Close(1.8705936669054204));
  // k = 10, N = 20: 2.920 * sqrt(110 / 120) = 2.7956871546; k = 2, N = 2:
  // 1.960 * sqrt(6 / 12) = 1.3859292911.
  CHECK(NemenyiCriticalDifference(10, 20, 0.10) == Close(2.7956871546485074));
  CHECK(NemenyiCriticalDifference(2, 2, 0.05) == Close(1.3859292911256331));

  CHECK_THAT(InvalidArgument([] { NemenyiCriticalValue(1, 0.05); }),
             Contains("tabulated for 2 to 10 conditions, got 1"));
  CHECK_THAT(InvalidArgument([] { NemenyiCriticalValue(11, 0.05); }),
             Contains("tabulated for 2 to 10 conditions, got 11"));
  CHECK_THAT(InvalidArgument([] { NemenyiCriticalValue(4, 0.01); }),
             Contains("tabulated for alpha 0.05 and 0.10, got 0.01"));
  CHECK_THAT(InvalidArgument([] { NemenyiCriticalDifference(4, 1, 0.05); }),
             Contains("expected at least 2 participants, got 1"));
}

TEST_CASE("NemenyiPostHoc: the thesis's pairs", "[study][stats]") {
  const auto friedman = haptel::study::FriedmanTest(kThesis);
  // Mean ranks 3.3 3.5 2.2 1.0: differences 0.2 1.1 2.3 1.3 2.5 1.2 for the
  // pairs (0,1) (0,2) (0,3) (1,2) (1,3) (2,3). CD 2.098 at 0.05 and 1.871 at
  // 0.10: only gesture against both cockpits differs, at either level.
  const std::vector<double> differences = {0.2, 1.1, 2.3, 1.3, 2.5, 1.2};
  const std::vector<bool> significant = {false, false, true, false, true, false};
  for (double alpha : {0.05, 0.10}) {
    const auto post_hoc = haptel::study::NemenyiPostHoc(friedman, alpha);
    CHECK(post_hoc.method == (alpha == 0.05 ? "Nemenyi (Demšar 2006), alpha 0.05"
                                            : "Nemenyi (Demšar 2006), alpha 0.10"));
    CHECK(post_hoc.alpha == alpha);
    REQUIRE(post_hoc.pairs.size() == 6);
    const int expected_pairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    for (std::size_t i = 0; i < 6; ++i) {
      const auto& pair = post_hoc.pairs[i];
      CHECK(pair.condition_a == expected_pairs[i][0]);
      CHECK(pair.condition_b == expected_pairs[i][1]);
      CHECK(pair.statistic == Close(differences[i]));
      REQUIRE(pair.critical_difference.has_value());
      CHECK(*pair.critical_difference ==
            Close(alpha == 0.05 ? 2.0975797164033283 : 1.8705936669054204));
      CHECK_FALSE(pair.p_value.has_value());
      CHECK(pair.significant == significant[i]);
    }
  }
}

TEST_CASE("WilcoxonSignedRank: exact p without ties or zeros", "[study][stats]") {
  const std::vector<double> x = {1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30};
  const std::vector<double> y = {0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29};
  const auto r = haptel::study::WilcoxonSignedRank(x, y);
  // |d| ranks: 0.01 -> 1, 0.08 -> 2 (negative), 0.147 -> 3 (negative), ...
  // W- = 2 + 3 = 5, W+ = 45 - 5 = 40. Subsets of 1..9 summing to <= 5:
  // {}, 1, 2, 3, 12, 4, 13, 5, 14, 23 = 10 of 512, so p = 2 * 10 / 512.
  CHECK(r.pairs_used == 9);
  CHECK(r.zero_differences == 0);
  CHECK(r.rank_sum_negative == 5.0);
  CHECK(r.rank_sum_positive == 40.0);
  CHECK(r.statistic == 5.0);
  CHECK(r.exact);
  CHECK_FALSE(r.z.has_value());
  CHECK(r.p_value == Close(0.0390625));
  // The test is symmetric in its samples.
  const auto swapped = haptel::study::WilcoxonSignedRank(y, x);
  CHECK(swapped.statistic == 5.0);
  CHECK(swapped.rank_sum_positive == 5.0);
  CHECK(swapped.p_value == Close(0.0390625));

  // All 5 differences one way: T = 0, p = 2 / 2^5 (thesis: HUD vs assisted).
  const auto all_faster = haptel::study::WilcoxonSignedRank(Column(kThesis, 1), Column(kThesis, 2));
  CHECK(all_faster.statistic == 0.0);
  CHECK(all_faster.exact);
  CHECK(all_faster.p_value == Close(0.0625));
  // The centre of the distribution: p = 1 (n = 4, W+ = W- = 5).
  CHECK(haptel::study::WilcoxonSignedRank({1, 2, 3, 4}, {0, 0, 3.5, 8}).p_value == Close(1.0));
}

TEST_CASE("WilcoxonSignedRank: exact up to 25 pairs, normal approximation above",
          "[study][stats]") {
  std::vector<double> x;
  std::vector<double> y;
  for (int i = 0; i < 30; ++i) {
    y.push_back(i);
    x.push_back(i + 0.25 * (i + 1) * (i % 4 == 0 ? -1 : 1));
  }
  const auto n30 = haptel::study::WilcoxonSignedRank(x, y);
  CHECK_FALSE(n30.exact);
  CHECK(n30.pairs_used == 30);
  CHECK(n30.statistic == 120.0);
  CHECK(n30.p_value == Close(0.02067111356691231));
  REQUIRE(n30.z.has_value());
  CHECK(*n30.z < 0.0);

  x.resize(25);
  y.resize(25);
  const auto n25 = haptel::study::WilcoxonSignedRank(x, y);
  CHECK(n25.exact);
  CHECK(n25.statistic == 91.0);
  CHECK(n25.p_value == Close(0.055070459842681885));
}

TEST_CASE("WilcoxonSignedRank: zeros dropped, ties corrected, normal approximation",
          "[study][stats]") {
  // d = 0 1 2 0 -2 2 0 3 2 -2 3 2: three zeros dropped, n = 9; |d| = 1 (rank 1),
  // six 2s (ranks 2..7, 4.5 each), two 3s (8.5 each); W- = 4.5 + 4.5 = 9.
  const auto zeros =
      haptel::study::WilcoxonSignedRank({10, 12, 14, 15, 9, 11, 13, 16, 12, 10, 17, 14},
                                        {10, 11, 12, 15, 11, 9, 13, 13, 10, 12, 14, 12});
  CHECK(zeros.zero_differences == 3);
  CHECK(zeros.pairs_used == 9);
  CHECK(zeros.rank_sum_negative == 9.0);
  CHECK(zeros.rank_sum_positive == 36.0);
  CHECK(zeros.statistic == 9.0);
  CHECK_FALSE(zeros.exact);
  CHECK(zeros.p_value == Close(0.098458502377584176));

  // Ties without zeros: still the normal approximation (n = 7 <= 25).
  const auto ties = haptel::study::WilcoxonSignedRank({5.0, 7.0, 6.0, 9.0, 4.0, 8.0, 6.5},
                                                      {4.0, 5.0, 7.0, 6.0, 3.0, 6.0, 8.5});
  CHECK_FALSE(ties.exact);
  CHECK(ties.zero_differences == 0);
  CHECK(ties.statistic == 7.0);
  CHECK(ties.p_value == Close(0.22994905679421362));

  // The thesis: simple cockpit vs gesture (110 s twice) and vs HUD (a zero).
  const auto gesture = haptel::study::WilcoxonSignedRank(Column(kThesis, 0), Column(kThesis, 3));
  CHECK(gesture.statistic == 0.0);
  CHECK(gesture.p_value == Close(0.042168197097155961));
  const auto hud = haptel::study::WilcoxonSignedRank(Column(kThesis, 0), Column(kThesis, 1));
  CHECK(hud.statistic == 5.0);
  CHECK(hud.zero_differences == 1);
  CHECK(hud.p_value == Close(1.0));
}

TEST_CASE("WilcoxonSignedRank: refuses what it cannot test", "[study][stats]") {
  using haptel::study::WilcoxonSignedRank;
  CHECK_THAT(InvalidArgument([] {
               WilcoxonSignedRank({1, 2, 3}, {1, 2});
             }),
             Contains("expected paired samples of equal length, got 3 and 2"));
  CHECK_THAT(InvalidArgument([] { WilcoxonSignedRank({}, {}); }),
             Contains("expected at least 1 pair, got none"));
  CHECK_THAT(InvalidArgument([] {
               WilcoxonSignedRank({1, kNaN}, {1, 2});
             }),
             Contains("first sample: expected finite values, got nan at index 1"));
  CHECK_THAT(InvalidArgument([] {
               WilcoxonSignedRank({1, 2}, {-kInf, 2});
             }),
             Contains("second sample: expected finite values, got -inf at index 0"));
  CHECK_THAT(InvalidArgument([] {
               WilcoxonSignedRank({1, 2, 3}, {1, 2, 3});
             }),
             Contains("all 3 differences are zero; expected at least one nonzero difference"));
}

TEST_CASE("HolmAdjust: step-down, monotone, capped at 1", "[study][stats]") {
  using haptel::study::HolmAdjust;
  // Sorted: 0.005 * 4 = 0.02, 0.01 * 3 = 0.03, 0.03 * 2 = 0.06, 0.04 * 1 = 0.04
  // -> kept at 0.06 so that a larger raw p never gets a smaller adjusted one.
  const auto adjusted = HolmAdjust({0.01, 0.04, 0.03, 0.005});
  REQUIRE(adjusted.size() == 4);
  CHECK(adjusted[0] == Close(0.03));
  CHECK(adjusted[1] == Close(0.06));
  CHECK(adjusted[2] == Close(0.06));
  CHECK(adjusted[3] == Close(0.02));
  // 0.5 * 2 = 1 and 0.6 -> 1: never above 1.
  CHECK(HolmAdjust({0.5, 0.6}) == std::vector<double>{1.0, 1.0});
  CHECK(HolmAdjust({0.7, 0.9}) == std::vector<double>{1.0, 1.0});
  // Equal raw p: 0.02 * 3 = 0.06, 0.02 * 2 = 0.04 -> 0.06, 0.5 * 1.
  const auto tied = HolmAdjust({0.02, 0.02, 0.5});
  CHECK(tied[0] == Close(0.06));
  CHECK(tied[1] == Close(0.06));
  CHECK(tied[2] == Close(0.5));
  CHECK(HolmAdjust({0.04}) == std::vector<double>{0.04});
  CHECK(HolmAdjust({}).empty());

  CHECK_THAT(InvalidArgument([] {
               HolmAdjust({0.1, 1.5});
             }),
             Contains("expected p-values in [0, 1], got 1.5 at index 1"));
  CHECK_THAT(InvalidArgument([] { HolmAdjust({-0.1}); }), Contains("got -0.1 at index 0"));
  CHECK_THAT(InvalidArgument([] { HolmAdjust({kNaN}); }), Contains("got nan at index 0"));
}

TEST_CASE("WilcoxonHolmPostHoc: the thesis's pairs", "[study][stats]") {
  const auto post_hoc = haptel::study::WilcoxonHolmPostHoc(kThesis, 0.05);
  CHECK(post_hoc.method == "Wilcoxon signed-rank, Holm-adjusted, alpha 0.05");
  REQUIRE(post_hoc.pairs.size() == 6);
  // From the script: T per pair, and Holm over the raw p 1, 0.125 (exact),
  // 0.0421681970971560 (ties: approximation), 0.0625, 0.0625, 0.0625 (exact).
  const std::vector<double> statistics = {5, 1, 0, 0, 0, 0};
  const std::vector<double> adjusted = {1, 0.3125, 0.25300918258293575, 0.3125, 0.3125, 0.3125};
  for (std::size_t i = 0; i < 6; ++i) {
    const auto& pair = post_hoc.pairs[i];
    CHECK(pair.statistic == statistics[i]);
    REQUIRE(pair.p_value.has_value());
    CHECK(*pair.p_value == Close(adjusted[i]));
    CHECK_FALSE(pair.critical_difference.has_value());
    CHECK_FALSE(pair.significant);
  }
  // alpha 0.30: the 0.253 pair (simple cockpit vs gesture) is significant.
  const auto lenient = haptel::study::WilcoxonHolmPostHoc(kThesis, 0.3);
  CHECK(lenient.method == "Wilcoxon signed-rank, Holm-adjusted, alpha 0.30");
  CHECK(lenient.pairs[2].significant);
  CHECK_FALSE(lenient.pairs[1].significant);

  // A pair that never differs is no evidence: p = 1, not an error.
  const auto same = haptel::study::WilcoxonHolmPostHoc({{1, 1, 2}, {3, 3, 1}, {2, 2, 5}}, 0.05);
  CHECK(same.pairs[0].statistic == 0.0);
  CHECK(*same.pairs[0].p_value == 1.0);

  CHECK_THAT(InvalidArgument([] { haptel::study::WilcoxonHolmPostHoc(kThesis, 0.0); }),
             Contains("expected alpha in (0, 1), got 0"));
  CHECK_THAT(InvalidArgument([] { haptel::study::WilcoxonHolmPostHoc(kThesis, 1.0); }),
             Contains("expected alpha in (0, 1), got 1"));
  CHECK_THAT(InvalidArgument([] {
               haptel::study::WilcoxonHolmPostHoc({{1, 2}, {1}}, 0.05);
             }),
             Contains("row 1 has 1"));
}

TEST_CASE("AnalyzeWithinSubject: everything the report prints", "[study][stats]") {
  using haptel::study::PostHocMethod;
  const auto nemenyi = haptel::study::AnalyzeWithinSubject(kThesis, PostHocMethod::kNemenyi, 0.05);
  CHECK(nemenyi.friedman.chi_square == Close(12.183673469387752));
  CHECK(nemenyi.friedman.kendall_w == Close(1194.0 / 1470.0));
  CHECK(nemenyi.post_hoc.method == "Nemenyi (Demšar 2006), alpha 0.05");
  CHECK(nemenyi.post_hoc.pairs.size() == 6);
  const auto wilcoxon =
      haptel::study::AnalyzeWithinSubject(kThesis, PostHocMethod::kWilcoxonHolm, 0.05);
  CHECK(wilcoxon.friedman.p_value_asymptotic == Close(0.0067797401305199397));
  // Exact, as the brute force of "exact p with ties" finds: 9168 of the 24^5
  // orderings are as extreme. The χ² overstates it almost sixfold here.
  CHECK(wilcoxon.friedman.p_exact);
  CHECK(wilcoxon.friedman.p_value == Close(9168.0 / 7962624.0));
  CHECK(wilcoxon.post_hoc.method == "Wilcoxon signed-rank, Holm-adjusted, alpha 0.05");
  CHECK_THAT(InvalidArgument([] {
               haptel::study::AnalyzeWithinSubject(kThesis, PostHocMethod::kNemenyi, 0.01);
             }),
             Contains("alpha 0.05 and 0.10, got 0.01"));
}

TEST_CASE("Special functions and ranks refuse their domain's outside", "[study][stats]") {
  using haptel::study::ChiSquareSurvival;
  using haptel::study::RegularizedUpperGamma;
  CHECK_THAT(InvalidArgument([] { RegularizedUpperGamma(0.0, 1.0); }),
             Contains("expected finite a > 0 and x >= 0, got a = 0, x = 1"));
  CHECK_THAT(InvalidArgument([] { RegularizedUpperGamma(1.0, -1.0); }),
             Contains("got a = 1, x = -1"));
  CHECK_THAT(InvalidArgument([] { RegularizedUpperGamma(kNaN, 1.0); }), Contains("got a = nan"));
  CHECK_THAT(InvalidArgument([] { RegularizedUpperGamma(1.0, kInf); }), Contains("x = inf"));
  CHECK_THAT(InvalidArgument([] { ChiSquareSurvival(1.0, 0); }),
             Contains("expected at least 1 degree of freedom, got 0"));
  CHECK_THAT(InvalidArgument([] { ChiSquareSurvival(-0.5, 2); }),
             Contains("expected a finite chi-square >= 0, got -0.5"));
  CHECK_THAT(InvalidArgument([] {
               haptel::study::Ranks({1, kNaN});
             }),
             Contains("Ranks: expected finite values, got nan at index 1"));
}
