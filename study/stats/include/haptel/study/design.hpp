#pragma once
/// @file The order in which each participant of a within-subject study runs
/// the conditions, and a check of how well an order design is balanced.
///
/// Conditions are indices 0..k−1 (the columns of the study's BlockMatrix).
/// A design gives each participant a sequence: element p is the condition run
/// at position p + 1. Learning and fatigue make the position matter, and the
/// condition run just before can carry over into the next; a balanced design
/// spreads both evenly over the conditions so they do not bias the comparison.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace haptel::study {

/// For each participant (index 0..N−1), the conditions in the order run.
using ConditionOrders = std::vector<std::vector<int>>;

/// The rows of Williams' balanced Latin square for k ≥ 2 conditions.
///
/// Row 0 is 0, 1, k−1, 2, k−2, 3, ...; row i adds i to every entry (mod k).
/// For even k these k rows put each condition once at each position and each
/// ordered pair (a directly followed by b, a ≠ b) exactly once. For odd k no
/// k rows can do that, so the square is followed by its mirror (each row
/// reversed): 2k rows, each condition twice per position, each ordered pair
/// exactly twice.
std::vector<std::vector<int>> WilliamsRows(int conditions);

/// Participant i runs row i mod rows of WilliamsRows(conditions), `repetitions`
/// times over. The design is only balanced over whole sets of rows, so
/// `participants` must be a multiple of k (even k) or 2k (odd k); otherwise
/// std::invalid_argument says so, e.g. "a balanced Latin square of 4
/// conditions needs a multiple of 4 participants, got 3". With repetitions,
/// the seam (last condition, then first again) is one more adjacent pair per
/// repetition that the square does not balance.
ConditionOrders BalancedLatinSquareOrders(int conditions, int participants, int repetitions = 1);

/// An independent uniformly random order for each participant, the same for
/// the same arguments on every run and platform.
///
/// Participant i's order is a Fisher–Yates shuffle of 0..k−1 (swapping
/// position j = k−1 down to 1 with a position drawn uniformly from 0..j) driven
/// by std::mt19937_64 seeded with std::seed_seq{low 32 bits of seed, high 32
/// bits of seed, i}; both are specified bit for bit by the C++ standard. The
/// uniform draw below a bound n rejects the engine's outputs under 2^64 mod n
/// and takes the rest mod n (unbiased; std::uniform_int_distribution and
/// std::shuffle are not portable: their algorithms are the library's choice).
/// Adding participants leaves the earlier participants' orders unchanged.
ConditionOrders RandomOrders(int conditions, int participants, std::uint64_t seed,
                             int repetitions = 1);

/// Every participant runs `order` (each of 0..k−1 exactly once, k = its size).
ConditionOrders FixedOrders(const std::vector<int>& order, int participants, int repetitions = 1);

/// How a study orders its conditions; the names are the study file's words.
enum class OrderDesignKind {
  kBalancedLatinSquare,  ///< "balanced-latin-square": BalancedLatinSquareOrders
  kRandom,               ///< "random": RandomOrders
  kFixed,                ///< "fixed": FixedOrders
};

/// "balanced-latin-square", "random" or "fixed".
std::string_view OrderDesignName(OrderDesignKind kind);
/// The kind named `name`; std::invalid_argument listing the three names otherwise.
OrderDesignKind ParseOrderDesignKind(std::string_view name);

/// An order design as a study file states it.
struct OrderDesign {
  OrderDesignKind kind = OrderDesignKind::kBalancedLatinSquare;
  int conditions = 0;    ///< k ≥ 1 (≥ 2 for the Latin square)
  int participants = 0;  ///< N ≥ 1
  /// r ≥ 1: each participant runs their whole sequence r times in a row
  /// (a, b, c, a, b, c for r = 2), so the study records r laps per condition.
  int repetitions = 1;
  std::uint64_t seed = 0;        ///< kRandom only
  std::vector<int> fixed_order;  ///< kFixed only: a permutation of 0..conditions−1
};

/// The orders `design` asks for; the same std::invalid_argument as the
/// function of its kind, or when fixed_order does not have `conditions` entries.
ConditionOrders MakeConditionOrders(const OrderDesign& design);

/// Counts that show how balanced a set of orders is.
struct DesignBalance {
  /// position_counts[p][c]: participants who run condition c at position p + 1.
  std::vector<std::vector<int>> position_counts;
  /// adjacent_pair_counts[a][b]: how often b is run directly after a, over all
  /// participants (with repetitions, also across the seam of two repetitions).
  std::vector<std::vector<int>> adjacent_pair_counts;
  /// Each participant runs every condition equally often.
  bool every_sequence_complete = false;
  /// At every position every condition is run equally often.
  bool positions_balanced = false;
  /// Every ordered pair of distinct conditions is adjacent equally often, and
  /// no condition directly follows itself: carry-over is balanced.
  bool carry_over_balanced = false;
};

/// Counts positions and ordered adjacent pairs of `orders` over `conditions`
/// conditions. std::invalid_argument when there are no participants, the
/// sequences differ in length or are empty, or hold an index outside 0..k−1.
DesignBalance CheckBalance(const ConditionOrders& orders, int conditions);

}  // namespace haptel::study
