#include "haptel/study/statistics.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <tuple>

namespace haptel::study {
namespace {

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// "0.05", "0.10", "0.01", "0.001": two decimals unless that would lose digits.
std::string AlphaText(double alpha) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", alpha);
  if (std::abs(std::strtod(buf, nullptr) - alpha) < 1e-12) return buf;
  return Number(alpha);
}

void RequireFinite(const std::vector<double>& values, const std::string& what) {
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw std::invalid_argument(what + ": expected finite values, got " + Number(values[i]) +
                                  " at index " + std::to_string(i));
    }
  }
}

/// Σ(t³ − t) over the groups of t equal values: what ties take from the
/// variance of ranks.
double TieTerm(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  double term = 0.0;
  for (std::size_t first = 0; first < values.size();) {
    std::size_t last = first;
    while (last + 1 < values.size() && values[last + 1] == values[first]) ++last;
    const double t = static_cast<double>(last - first + 1);
    term += t * t * t - t;
    first = last + 1;
  }
  return term;
}

/// The checked matrix's ranks and what Friedman's χ² and Kendall's W share.
struct RankSummary {
  int rows = 0;
  int columns = 0;
  std::vector<double> rank_sums;
  double spread = 0.0;    ///< S = Σ_j (R_j − N(k+1)/2)²
  double tie_term = 0.0;  ///< T = Σ over rows of Σ(t³ − t)
  /// N(k³ − k) − T: N times what S would be at most without ties, over 12.
  double tie_corrected_total = 0.0;
};

/// Throws unless `values` has at least 2 rows of the same k >= 2 finite values.
void CheckShape(const BlockMatrix& values) {
  if (values.size() < 2) {
    throw std::invalid_argument(
        "within-subject statistics: expected at least 2 participants (rows), got " +
        std::to_string(values.size()));
  }
  const std::size_t k = values.front().size();
  if (k < 2) {
    throw std::invalid_argument(
        "within-subject statistics: expected at least 2 conditions (columns), got " +
        std::to_string(k));
  }
  for (std::size_t row = 0; row < values.size(); ++row) {
    if (values[row].size() != k) {
      throw std::invalid_argument("within-subject statistics: expected every row to have " +
                                  std::to_string(k) + " values (as row 0 has), row " +
                                  std::to_string(row) + " has " +
                                  std::to_string(values[row].size()));
    }
    RequireFinite(values[row], "within-subject statistics, row " + std::to_string(row));
  }
}

RankSummary SummarizeRanks(const BlockMatrix& values) {
  CheckShape(values);
  const std::size_t k = values.front().size();
  RankSummary summary;
  summary.rows = static_cast<int>(values.size());
  summary.columns = static_cast<int>(k);
  summary.rank_sums.assign(k, 0.0);
  for (const auto& row : values) {
    const std::vector<double> ranks = Ranks(row);
    for (std::size_t j = 0; j < k; ++j) summary.rank_sums[j] += ranks[j];
    summary.tie_term += TieTerm(row);
  }
  const double n = summary.rows;
  const double kd = summary.columns;
  const double expected_rank_sum = n * (kd + 1.0) / 2.0;
  for (double r : summary.rank_sums) {
    summary.spread += (r - expected_rank_sum) * (r - expected_rank_sum);
  }
  summary.tie_corrected_total = n * (kd * kd * kd - kd) - summary.tie_term;
  if (summary.tie_corrected_total <= 0.0) {
    throw std::invalid_argument(
        "within-subject statistics: every participant has the same value for all " +
        std::to_string(k) + " conditions; there is no ranking to test");
  }
  return summary;
}

double KendallWOf(const RankSummary& s) {
  return 12.0 * s.spread / (s.rows * s.tie_corrected_total);
}

/// Two-sided exact p of W+ = `rank_sum_positive` under H0 (each sign ±
/// with probability ½, independently). Ranks are doubled so that half
/// ranks would count too; the subset sums are counted by dynamic programming.
double ExactSignedRankP(const std::vector<double>& ranks, double rank_sum_positive) {
  std::vector<int> doubled(ranks.size());
  int total = 0;
  for (std::size_t i = 0; i < ranks.size(); ++i) {
    doubled[i] = static_cast<int>(std::lround(2.0 * ranks[i]));
    total += doubled[i];
  }
  // ways[s]: sign assignments whose doubled W+ is s (exact in a double up to 2^53).
  std::vector<double> ways(static_cast<std::size_t>(total) + 1, 0.0);
  ways[0] = 1.0;
  int reached = 0;
  for (int w : doubled) {
    for (int s = reached; s >= 0; --s) ways[static_cast<std::size_t>(s + w)] += ways[s];
    reached += w;
  }
  const double assignments = std::ldexp(1.0, static_cast<int>(ranks.size()));
  const int observed = static_cast<int>(std::lround(2.0 * rank_sum_positive));
  double at_most = 0.0;
  double at_least = 0.0;
  for (int s = 0; s <= total; ++s) {
    if (s <= observed) at_most += ways[static_cast<std::size_t>(s)];
    if (s >= observed) at_least += ways[static_cast<std::size_t>(s)];
  }
  return std::min(1.0, 2.0 * std::min(at_most, at_least) / assignments);
}

constexpr int kMaxExactPairs = 25;

/// A row's ranks doubled, so that midranks (multiples of ½) are integers.
std::vector<std::int64_t> DoubledRanks(const std::vector<double>& row) {
  std::vector<std::int64_t> doubled;
  for (double r : Ranks(row)) doubled.push_back(std::llround(2.0 * r));
  return doubled;
}

/// 4 S = Σ_j (2 R_j − N(k + 1))² from the doubled rank sums: an integer, so
/// the exact p compares statistics without rounding.
std::int64_t QuadrupledSpread(const std::vector<std::int64_t>& doubled_sums, std::int64_t rows) {
  const std::int64_t doubled_expected = rows * static_cast<std::int64_t>(doubled_sums.size() + 1);
  std::int64_t spread = 0;
  for (std::int64_t sum : doubled_sums)
    spread += (sum - doubled_expected) * (sum - doubled_expected);
  return spread;
}

/// The null distribution of Friedman's S for one set of rows: the values 4S
/// takes, ascending, and P(4S ≥ each).
struct FriedmanNullDistribution {
  std::vector<std::int64_t> quadrupled_spread;
  std::vector<double> at_least;
};

/// What a null distribution depends on: each row's doubled ranks sorted (the
/// multiset the row permutes), the rows sorted too (their order does not
/// matter), and the step limit. Every untied study of N participants and k
/// conditions has the same key, so EstimatePower computes it once per N.
struct FriedmanNullKey {
  std::vector<std::vector<std::int64_t>> sorted_rows;
  long max_steps = 0;
  bool operator<(const FriedmanNullKey& other) const {
    return std::tie(max_steps, sorted_rows) < std::tie(other.max_steps, other.sorted_rows);
  }
};

/// Friedman's null distribution by dynamic programming, or nothing past
/// `key.max_steps` steps (see kFriedmanExactMaxSteps).
std::optional<FriedmanNullDistribution> ComputeFriedmanNull(const FriedmanNullKey& key) {
  const auto& sorted_rows = key.sorted_rows;
  const int k = static_cast<int>(sorted_rows.front().size());
  const std::int64_t n = static_cast<std::int64_t>(sorted_rows.size());

  // Every distinct ordering of a row's ranks once: with ties each stands for
  // the same number (Π t!) of the k! orderings, so all are equally likely.
  // Rows with the same ranks share one list.
  std::map<std::vector<std::int64_t>, std::vector<std::vector<std::int64_t>>> orderings_of;
  std::vector<const std::vector<std::vector<std::int64_t>>*> row_orderings;
  long remaining_orderings = 0;
  for (const auto& sorted : sorted_rows) {
    auto [it, inserted] = orderings_of.try_emplace(sorted);
    if (inserted) {
      std::vector<std::int64_t> ordering = sorted;
      do {
        it->second.push_back(ordering);
      } while (std::next_permutation(ordering.begin(), ordering.end()));
    }
    row_orderings.push_back(&it->second);
    remaining_orderings += static_cast<long>(it->second.size());
  }

  // H0 treats the conditions alike, so the distribution of the partial rank
  // sums is the same under every order of the conditions: the programme keeps
  // one sorted vector per set of reorderings, with their total probability
  // (up to k! times fewer states), and S does not depend on the order. A
  // state's key packs its k − 1 smallest sums (the largest follows from their
  // fixed total) in base 2kN + 1, the largest doubled rank sum being 2kN.
  const std::uint64_t base = static_cast<std::uint64_t>(2 * k * n + 1);
  double key_range = 1.0;
  for (int j = 0; j + 1 < k; ++j) key_range *= static_cast<double>(base);
  if (key_range > 9.0e18) return std::nullopt;  // would not fit the packed key
  const auto pack = [&](const std::int64_t* ascending) {
    std::uint64_t packed = 0;
    for (int j = k - 2; j >= 0; --j)
      packed = packed * base + static_cast<std::uint64_t>(ascending[j]);
    return packed;
  };

  using Sums = std::array<std::int64_t, kFriedmanExactMaxConditions>;
  struct State {
    Sums sums;  // doubled partial rank sums, ascending; unused entries 0
    double probability;
  };
  std::vector<State> states{{Sums{}, 1.0}};
  std::vector<State> next;
  // Open addressing from a packed state to its index in `next`:
  // std::unordered_map's node per entry made a call several times slower.
  constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  std::vector<std::uint64_t> slot_keys;
  std::vector<std::size_t> slot_index;
  int slot_bits = 0;
  const auto slot_of = [&](std::uint64_t packed) {
    return static_cast<std::size_t>((packed * 0x9E3779B97F4A7C15ull) >> (64 - slot_bits));
  };
  const auto clear_slots = [&](int bits) {
    slot_bits = bits;
    slot_keys.assign(std::size_t{1} << bits, kEmpty);
    slot_index.assign(std::size_t{1} << bits, 0);
  };

  long steps = 0;
  for (const auto* orderings : row_orderings) {
    // The states never become fewer (sort(c + o) for the ascending ordering o
    // is c + o, one new state per old one), so this row and the rest take at
    // least states × their orderings steps: give up now rather than later.
    if (steps + static_cast<long>(states.size()) * remaining_orderings > key.max_steps)
      return std::nullopt;
    remaining_orderings -= static_cast<long>(orderings->size());
    steps += static_cast<long>(states.size() * orderings->size());

    const double weight = 1.0 / static_cast<double>(orderings->size());
    next.clear();
    int bits = 10;
    while ((std::size_t{1} << bits) < 2 * states.size()) ++bits;
    clear_slots(bits);
    for (const State& state : states) {
      for (const auto& ordering : *orderings) {
        State candidate{Sums{}, state.probability * weight};
        for (int j = 0; j < k; ++j) {
          const auto at = static_cast<std::size_t>(j);
          candidate.sums[at] = state.sums[at] + ordering[at];
        }
        // Insertion sort: k ≤ 6 values, nearly in order already.
        for (int j = 1; j < k; ++j) {
          const std::int64_t value = candidate.sums[static_cast<std::size_t>(j)];
          int i = j - 1;
          for (; i >= 0 && candidate.sums[static_cast<std::size_t>(i)] > value; --i) {
            candidate.sums[static_cast<std::size_t>(i + 1)] =
                candidate.sums[static_cast<std::size_t>(i)];
          }
          candidate.sums[static_cast<std::size_t>(i + 1)] = value;
        }
        const std::uint64_t packed = pack(candidate.sums.data());
        std::size_t slot = slot_of(packed);
        while (slot_keys[slot] != kEmpty && slot_keys[slot] != packed)
          slot = (slot + 1) & (slot_keys.size() - 1);
        if (slot_keys[slot] == packed) {
          next[slot_index[slot]].probability += candidate.probability;
          continue;
        }
        slot_keys[slot] = packed;
        slot_index[slot] = next.size();
        next.push_back(candidate);
        if (2 * next.size() > slot_keys.size()) {  // keep the table at most half full
          clear_slots(slot_bits + 1);
          for (std::size_t i = 0; i < next.size(); ++i) {
            const std::uint64_t moved = pack(next[i].sums.data());
            std::size_t free_slot = slot_of(moved);
            while (slot_keys[free_slot] != kEmpty)
              free_slot = (free_slot + 1) & (slot_keys.size() - 1);
            slot_keys[free_slot] = moved;
            slot_index[free_slot] = i;
          }
        }
      }
    }
    states.swap(next);
  }

  // P(4S = s) per value, then the upper tail from the largest value down.
  std::map<std::int64_t, double> by_spread;
  std::vector<std::int64_t> sums(static_cast<std::size_t>(k));
  for (const State& state : states) {
    std::copy(state.sums.begin(), state.sums.begin() + k, sums.begin());
    by_spread[QuadrupledSpread(sums, n)] += state.probability;
  }
  FriedmanNullDistribution null;
  null.quadrupled_spread.resize(by_spread.size());
  null.at_least.resize(by_spread.size());
  double tail = 0.0;
  std::size_t i = by_spread.size();
  for (auto it = by_spread.rbegin(); it != by_spread.rend(); ++it) {
    --i;
    tail += it->second;
    null.quadrupled_spread[i] = it->first;
    null.at_least[i] = std::min(1.0, tail);
  }
  return null;
}

/// ComputeFriedmanNull, remembered: EstimatePower asks for the same
/// distribution (and the same refusal) hundreds of times per participant
/// count. At most kMaxCached keys, emptied when full; each distribution holds
/// one entry per value of S. Guarded, as callers may run in threads.
std::shared_ptr<const std::optional<FriedmanNullDistribution>> CachedFriedmanNull(
    const FriedmanNullKey& key) {
  constexpr std::size_t kMaxCached = 32;
  static std::mutex mutex;
  static std::map<FriedmanNullKey, std::shared_ptr<const std::optional<FriedmanNullDistribution>>>
      cache;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    if (const auto it = cache.find(key); it != cache.end()) return it->second;
  }
  auto computed =
      std::make_shared<const std::optional<FriedmanNullDistribution>>(ComputeFriedmanNull(key));
  const std::lock_guard<std::mutex> lock(mutex);
  if (cache.size() >= kMaxCached) cache.clear();
  cache.emplace(key, computed);
  return computed;
}

}  // namespace

std::vector<double> Ranks(const std::vector<double>& values) {
  RequireFinite(values, "Ranks");
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(values.size());
  for (std::size_t first = 0; first < order.size();) {
    std::size_t last = first;
    while (last + 1 < order.size() && values[order[last + 1]] == values[order[first]]) ++last;
    // Positions first..last hold ranks first+1..last+1; ties share their mean.
    const double average = (static_cast<double>(first + last) + 2.0) / 2.0;
    for (std::size_t i = first; i <= last; ++i) ranks[order[i]] = average;
    first = last + 1;
  }
  return ranks;
}

double RegularizedUpperGamma(double a, double x) {
  if (!(a > 0.0) || !std::isfinite(a) || !(x >= 0.0) || !std::isfinite(x)) {
    throw std::invalid_argument(
        "RegularizedUpperGamma: expected finite a > 0 and x >= 0, got a = " + Number(a) +
        ", x = " + Number(x));
  }
  if (x == 0.0) return 1.0;
  constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
  constexpr int kMaxIterations = 100000;
  // x^a e^−x / Γ(a), the factor both expansions share. a > 0, so lgamma's sign is +.
  const double prefactor = std::exp(-x + a * std::log(x) - std::lgamma(a));
  if (x < a + 1.0) {
    // P(a, x) = prefactor Σ_n x^n / (a (a+1) ... (a+n)).
    double denominator = a;
    double term = 1.0 / a;
    double sum = term;
    for (int n = 0; n < kMaxIterations; ++n) {
      denominator += 1.0;
      term *= x / denominator;
      sum += term;
      if (std::abs(term) < std::abs(sum) * kEpsilon) return 1.0 - sum * prefactor;
    }
  } else {
    // Q(a, x) = prefactor / (x + 1 − a − 1(1−a)/(x + 3 − a − 2(2−a)/(x + 5 − a − ...))),
    // evaluated by the modified Lentz method.
    constexpr double kTiny = std::numeric_limits<double>::min() / kEpsilon;
    double b = x + 1.0 - a;
    double c = 1.0 / kTiny;
    double d = 1.0 / b;
    double fraction = d;
    for (int i = 1; i < kMaxIterations; ++i) {
      const double an = -i * (i - a);
      b += 2.0;
      d = an * d + b;
      if (std::abs(d) < kTiny) d = kTiny;
      c = b + an / c;
      if (std::abs(c) < kTiny) c = kTiny;
      d = 1.0 / d;
      const double step = d * c;
      fraction *= step;
      if (std::abs(step - 1.0) < kEpsilon) return prefactor * fraction;
    }
  }
  throw std::runtime_error("RegularizedUpperGamma: no convergence for a = " + Number(a) +
                           ", x = " + Number(x));
}

double ChiSquareSurvival(double chi_square, int degrees_of_freedom) {
  if (degrees_of_freedom < 1) {
    throw std::invalid_argument("ChiSquareSurvival: expected at least 1 degree of freedom, got " +
                                std::to_string(degrees_of_freedom));
  }
  if (!(chi_square >= 0.0) || !std::isfinite(chi_square)) {
    throw std::invalid_argument("ChiSquareSurvival: expected a finite chi-square >= 0, got " +
                                Number(chi_square));
  }
  return RegularizedUpperGamma(0.5 * degrees_of_freedom, 0.5 * chi_square);
}

namespace {

/// The continued fraction of I_x(a, b) (Numerical Recipes' betacf), by the
/// modified Lentz method.
double BetaContinuedFraction(double a, double b, double x) {
  constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
  constexpr double kTiny = std::numeric_limits<double>::min() / kEpsilon;
  constexpr int kMaxIterations = 100000;
  const double qab = a + b;
  const double qap = a + 1.0;
  const double qam = a - 1.0;
  double c = 1.0;
  double d = 1.0 - qab * x / qap;
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= kMaxIterations; ++m) {
    const double m2 = 2.0 * m;
    // The even step, then the odd step of the fraction.
    double aa = m * (b - m) * x / ((qam + m2) * (a + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2));
    d = 1.0 + aa * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + aa / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double step = d * c;
    h *= step;
    if (std::abs(step - 1.0) < kEpsilon) return h;
  }
  throw std::runtime_error("RegularizedIncompleteBeta: no convergence for a = " + Number(a) +
                           ", b = " + Number(b) + ", x = " + Number(x));
}

}  // namespace

double RegularizedIncompleteBeta(double a, double b, double x) {
  if (!(a > 0.0) || !std::isfinite(a) || !(b > 0.0) || !std::isfinite(b) ||
      !(x >= 0.0 && x <= 1.0)) {
    throw std::invalid_argument(
        "RegularizedIncompleteBeta: expected finite a > 0, b > 0 and x in [0, 1], got a = " +
        Number(a) + ", b = " + Number(b) + ", x = " + Number(x));
  }
  if (x == 0.0) return 0.0;
  if (x == 1.0) return 1.0;
  // x^a (1 − x)^b / (a B(a, b)), the fraction's prefactor, through logs.
  const double log_front =
      std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  if (x < (a + 1.0) / (a + b + 2.0))
    return std::exp(log_front) * BetaContinuedFraction(a, b, x) / a;
  return 1.0 - std::exp(log_front) * BetaContinuedFraction(b, a, 1.0 - x) / b;
}

double StudentTTwoSidedP(double t, double degrees_of_freedom) {
  if (!(degrees_of_freedom > 0.0) || !std::isfinite(degrees_of_freedom) || std::isnan(t)) {
    throw std::invalid_argument(
        "StudentTTwoSidedP: expected t not NaN and finite df > 0, got t = " + Number(t) +
        ", df = " + Number(degrees_of_freedom));
  }
  if (std::isinf(t)) return 0.0;
  return RegularizedIncompleteBeta(0.5 * degrees_of_freedom, 0.5,
                                   degrees_of_freedom / (degrees_of_freedom + t * t));
}

double StudentTQuantile(double probability, double degrees_of_freedom) {
  if (!(probability > 0.0 && probability < 1.0) || !(degrees_of_freedom > 0.0) ||
      !std::isfinite(degrees_of_freedom)) {
    throw std::invalid_argument(
        "StudentTQuantile: expected a probability in (0, 1) and finite df > 0, got " +
        Number(probability) + " and df = " + Number(degrees_of_freedom));
  }
  if (probability == 0.5) return 0.0;
  // The upper tail's two-sided p: P(|T| ≥ t) = 2 min(probability, 1 − probability).
  const double tail = 2.0 * std::min(probability, 1.0 - probability);
  double low = 0.0;
  double high = 1.0;
  while (StudentTTwoSidedP(high, degrees_of_freedom) > tail) {
    low = high;
    high *= 2.0;
    if (high > 1e300) break;
  }
  for (int i = 0; i < 2000 && high - low > 1e-13 * high; ++i) {
    const double middle = 0.5 * (low + high);
    (StudentTTwoSidedP(middle, degrees_of_freedom) > tail ? low : high) = middle;
  }
  const double t = 0.5 * (low + high);
  return probability > 0.5 ? t : -t;
}

std::optional<double> FriedmanExactP(const BlockMatrix& values, long max_steps) {
  CheckShape(values);
  const int k = static_cast<int>(values.front().size());
  if (k > kFriedmanExactMaxConditions) return std::nullopt;
  FriedmanNullKey key;
  key.max_steps = max_steps;
  std::vector<std::int64_t> observed_sums(static_cast<std::size_t>(k), 0);
  for (const auto& row : values) {
    std::vector<std::int64_t> doubled = DoubledRanks(row);
    for (int j = 0; j < k; ++j) {
      observed_sums[static_cast<std::size_t>(j)] += doubled[static_cast<std::size_t>(j)];
    }
    std::sort(doubled.begin(), doubled.end());
    key.sorted_rows.push_back(std::move(doubled));
  }
  std::sort(key.sorted_rows.begin(), key.sorted_rows.end());
  const std::int64_t observed =
      QuadrupledSpread(observed_sums, static_cast<std::int64_t>(values.size()));

  const auto null = CachedFriedmanNull(key);
  if (!null->has_value()) return std::nullopt;
  const FriedmanNullDistribution& distribution = **null;
  // The observed 4S is one of the values the distribution holds.
  const auto at = std::lower_bound(distribution.quadrupled_spread.begin(),
                                   distribution.quadrupled_spread.end(), observed);
  if (at == distribution.quadrupled_spread.end()) return 0.0;  // above every value; S_obs never is
  return distribution
      .at_least[static_cast<std::size_t>(at - distribution.quadrupled_spread.begin())];
}

FriedmanResult FriedmanTest(const BlockMatrix& values) {
  const RankSummary s = SummarizeRanks(values);
  FriedmanResult result;
  result.participants = s.rows;
  result.conditions = s.columns;
  for (double r : s.rank_sums) result.ranks.push_back({r, r / s.rows});
  result.degrees_of_freedom = s.columns - 1;
  result.chi_square = 12.0 * s.spread * (s.columns - 1) / s.tie_corrected_total;
  result.p_value_asymptotic = ChiSquareSurvival(result.chi_square, result.degrees_of_freedom);
  const std::optional<double> exact = FriedmanExactP(values);
  result.p_exact = exact.has_value();
  result.p_value = exact.value_or(result.p_value_asymptotic);
  result.kendall_w = KendallWOf(s);
  return result;
}

double KendallW(const BlockMatrix& values) { return KendallWOf(SummarizeRanks(values)); }

WilcoxonResult WilcoxonSignedRank(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() != y.size()) {
    throw std::invalid_argument(
        "Wilcoxon signed-rank: expected paired samples of equal length, got " +
        std::to_string(x.size()) + " and " + std::to_string(y.size()));
  }
  if (x.empty()) {
    throw std::invalid_argument("Wilcoxon signed-rank: expected at least 1 pair, got none");
  }
  RequireFinite(x, "Wilcoxon signed-rank, first sample");
  RequireFinite(y, "Wilcoxon signed-rank, second sample");

  WilcoxonResult result;
  std::vector<double> differences;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double d = x[i] - y[i];
    if (d == 0.0) {
      ++result.zero_differences;
    } else {
      differences.push_back(d);
    }
  }
  if (differences.empty()) {
    throw std::invalid_argument("Wilcoxon signed-rank: all " + std::to_string(x.size()) +
                                " differences are zero; expected at least one nonzero difference");
  }
  std::vector<double> magnitudes(differences.size());
  std::transform(differences.begin(), differences.end(), magnitudes.begin(),
                 [](double d) { return std::abs(d); });
  const std::vector<double> ranks = Ranks(magnitudes);
  for (std::size_t i = 0; i < differences.size(); ++i) {
    (differences[i] > 0.0 ? result.rank_sum_positive : result.rank_sum_negative) += ranks[i];
  }
  result.pairs_used = static_cast<int>(differences.size());
  result.statistic = std::min(result.rank_sum_positive, result.rank_sum_negative);

  const double tie_term = TieTerm(magnitudes);
  const double n = result.pairs_used;
  result.exact =
      result.pairs_used <= kMaxExactPairs && result.zero_differences == 0 && tie_term == 0.0;
  if (result.exact) {
    result.p_value = ExactSignedRankP(ranks, result.rank_sum_positive);
  } else {
    const double mean = n * (n + 1.0) / 4.0;
    const double variance = (n * (n + 1.0) * (2.0 * n + 1.0) - 0.5 * tie_term) / 24.0;
    const double z = (result.statistic - mean) / std::sqrt(variance);
    result.z = z;
    // 2 (1 − Φ(|z|)) without the cancellation of 1 − Φ.
    result.p_value = std::erfc(std::abs(z) / std::sqrt(2.0));
  }
  return result;
}

std::vector<double> HolmAdjust(const std::vector<double>& p_values) {
  for (std::size_t i = 0; i < p_values.size(); ++i) {
    if (!(p_values[i] >= 0.0 && p_values[i] <= 1.0)) {
      throw std::invalid_argument("HolmAdjust: expected p-values in [0, 1], got " +
                                  Number(p_values[i]) + " at index " + std::to_string(i));
    }
  }
  std::vector<std::size_t> order(p_values.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return p_values[a] < p_values[b]; });
  std::vector<double> adjusted(p_values.size());
  const double m = static_cast<double>(p_values.size());
  double running_max = 0.0;  // keeps the adjusted values in the order of the raw ones
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    const double scaled = std::min(1.0, (m - static_cast<double>(rank)) * p_values[order[rank]]);
    running_max = std::max(running_max, scaled);
    adjusted[order[rank]] = running_max;
  }
  return adjusted;
}

double NemenyiCriticalValue(int conditions, double alpha) {
  // Demšar (2006), "Statistical comparisons of classifiers over multiple data
  // sets", JMLR 7, Table 5(a): q_α for k = 2..10.
  static constexpr double kAlpha005[] = {1.960, 2.343, 2.569, 2.728, 2.850,
                                         2.949, 3.031, 3.102, 3.164};
  static constexpr double kAlpha010[] = {1.645, 2.052, 2.291, 2.459, 2.589,
                                         2.693, 2.780, 2.855, 2.920};
  if (conditions < 2 || conditions > 10) {
    throw std::invalid_argument(
        "Nemenyi: critical values are tabulated for 2 to 10 conditions, got " +
        std::to_string(conditions));
  }
  if (std::abs(alpha - 0.05) < 1e-12) return kAlpha005[conditions - 2];
  if (std::abs(alpha - 0.10) < 1e-12) return kAlpha010[conditions - 2];
  throw std::invalid_argument(
      "Nemenyi: critical values are tabulated for alpha 0.05 and 0.10, got " + Number(alpha));
}

double NemenyiCriticalDifference(int conditions, int participants, double alpha) {
  const double q = NemenyiCriticalValue(conditions, alpha);
  if (participants < 2) {
    throw std::invalid_argument("Nemenyi: expected at least 2 participants, got " +
                                std::to_string(participants));
  }
  const double k = conditions;
  return q * std::sqrt(k * (k + 1.0) / (6.0 * participants));
}

PostHocResult NemenyiPostHoc(const FriedmanResult& friedman, double alpha) {
  const double cd = NemenyiCriticalDifference(friedman.conditions, friedman.participants, alpha);
  if (friedman.ranks.size() != static_cast<std::size_t>(friedman.conditions)) {
    throw std::invalid_argument("Nemenyi: expected mean ranks of " +
                                std::to_string(friedman.conditions) + " conditions, got " +
                                std::to_string(friedman.ranks.size()));
  }
  PostHocResult result;
  result.method = "Nemenyi (Demšar 2006), alpha " + AlphaText(alpha);
  result.alpha = alpha;
  for (int a = 0; a < friedman.conditions; ++a) {
    for (int b = a + 1; b < friedman.conditions; ++b) {
      PairComparison pair;
      pair.condition_a = a;
      pair.condition_b = b;
      pair.statistic = std::abs(friedman.ranks[a].mean_rank - friedman.ranks[b].mean_rank);
      pair.critical_difference = cd;
      pair.significant = pair.statistic > cd;
      result.pairs.push_back(pair);
    }
  }
  return result;
}

PostHocResult WilcoxonHolmPostHoc(const BlockMatrix& values, double alpha) {
  if (!(alpha > 0.0 && alpha < 1.0)) {
    throw std::invalid_argument("Wilcoxon-Holm: expected alpha in (0, 1), got " + Number(alpha));
  }
  CheckShape(values);  // the same checks and messages as Friedman's test
  const int k = static_cast<int>(values.front().size());
  std::vector<std::vector<double>> columns(k);
  for (const auto& row : values) {
    for (int j = 0; j < k; ++j) columns[j].push_back(row[j]);
  }
  PostHocResult result;
  result.method = "Wilcoxon signed-rank, Holm-adjusted, alpha " + AlphaText(alpha);
  result.alpha = alpha;
  std::vector<double> raw_p;
  for (int a = 0; a < k; ++a) {
    for (int b = a + 1; b < k; ++b) {
      PairComparison pair;
      pair.condition_a = a;
      pair.condition_b = b;
      if (columns[a] == columns[b]) {
        raw_p.push_back(1.0);
      } else {
        const WilcoxonResult test = WilcoxonSignedRank(columns[a], columns[b]);
        pair.statistic = test.statistic;
        raw_p.push_back(test.p_value);
      }
      result.pairs.push_back(pair);
    }
  }
  const std::vector<double> adjusted = HolmAdjust(raw_p);
  for (std::size_t i = 0; i < result.pairs.size(); ++i) {
    result.pairs[i].p_value = adjusted[i];
    result.pairs[i].significant = adjusted[i] <= alpha;
  }
  return result;
}

WithinSubjectAnalysis AnalyzeWithinSubject(const BlockMatrix& values, PostHocMethod method,
                                           double alpha) {
  WithinSubjectAnalysis analysis;
  analysis.friedman = FriedmanTest(values);
  analysis.post_hoc = method == PostHocMethod::kNemenyi ? NemenyiPostHoc(analysis.friedman, alpha)
                                                        : WilcoxonHolmPostHoc(values, alpha);
  return analysis;
}

}  // namespace haptel::study
