// Order designs: Williams squares balanced for k = 2..8, the refusals of
// participant counts they cannot balance, random orders pinned to an
// independent implementation of the documented algorithm, fixed orders, and
// the balance check itself.
//
// The pinned random orders come from this Python (/usr/bin/python3), which
// writes std::seed_seq, std::mt19937_64 and the documented shuffle out from
// the C++ standard's text; its first two draws after seed_seq{1, 2, 3} match
// libstdc++'s (1831209241179374162, 4398843623863442686).
//
// clang-format off
//   # std::seed_seq, std::mt19937_64 and Haptel's documented shuffle, written out
//   # from the C++ standard's text ([rand.util.seedseq], [rand.eng.mers]).
//   M32, M64 = 0xFFFFFFFF, 0xFFFFFFFFFFFFFFFF
//
//   def seed_seq_generate(v, n):
//       b = [0x8B8B8B8B] * n
//       s = len(v)
//       t = 11 if n >= 623 else 7 if n >= 68 else 5 if n >= 39 else 3 if n >= 7 else (n - 1) // 2
//       p = (n - t) // 2
//       q = p + t
//       m = max(s + 1, n)
//       T = lambda x: x ^ (x >> 27)
//       for k in range(m):
//           r1 = 1664525 * T(b[k % n] ^ b[(k + p) % n] ^ b[(k - 1) % n]) & M32
//           r2 = (r1 + (s if k == 0 else (k % n + v[k - 1]) if k <= s else k % n)) & M32
//           b[(k + p) % n] = (b[(k + p) % n] + r1) & M32
//           b[(k + q) % n] = (b[(k + q) % n] + r2) & M32
//           b[k % n] = r2
//       for k in range(m, m + n):
//           r3 = 1566083941 * T((b[k % n] + b[(k + p) % n] + b[(k - 1) % n]) & M32) & M32
//           r4 = (r3 - k % n) & M32
//           b[(k + p) % n] ^= r3
//           b[(k + q) % n] ^= r4
//           b[k % n] = r4
//       return b
//
//   class MT64:
//       def __init__(self, state):
//           self.mt, self.i = list(state), 312
//       def __call__(self):
//           mt = self.mt
//           if self.i >= 312:
//               for i in range(312):
//                   x = (mt[i] & 0xFFFFFFFF80000000) | (mt[(i + 1) % 312] & 0x7FFFFFFF)
//                   mt[i] = mt[(i + 156) % 312] ^ (x >> 1) ^ (0xB5026F5AA96619E9 if x & 1 else 0)
//               self.i = 0
//           y = mt[self.i]
//           self.i += 1
//           y ^= (y >> 29) & 0x5555555555555555
//           y ^= (y << 17) & 0x71D67FFFEDA60000 & M64
//           y ^= (y << 37) & 0xFFF7EEE000000000 & M64
//           return y ^ (y >> 43)
//
//   def mt64_from_seed(seed):  # the integer seeding, only to check MT64 itself
//       x = [seed]
//       for i in range(1, 312):
//           x.append((6364136223846793005 * (x[-1] ^ (x[-1] >> 62)) + i) & M64)
//       return MT64(x)
//
//   def mt64_from_seed_seq(words):
//       a = seed_seq_generate(words, 624)
//       return MT64([a[2 * i] | (a[2 * i + 1] << 32) for i in range(312)])
//
//   g = mt64_from_seed(5489)
//   for _ in range(9999): g()
//   assert g() == 9981545732273789042  # the standard's check of mt19937_64
//
//   def below(g, bound):
//       rejected_below = (2 ** 64 - bound) % bound
//       while True:
//           x = g()
//           if x >= rejected_below:
//               return x % bound
//
//   def random_order(k, seed, i):
//       g = mt64_from_seed_seq([seed & M32, seed >> 32, i])
//       order = list(range(k))
//       for j in range(k - 1, 0, -1):
//           pick = below(g, j + 1)
//           order[j], order[pick] = order[pick], order[j]
//       return order
//
//   g = mt64_from_seed_seq([1, 2, 3])
//   print("first draws after seed_seq{1, 2, 3}:", g(), g())
//   for seed in (42, 0x123456789ABCDEF0):
//       print(hex(seed), [random_order(6, seed, i) for i in range(4)])
//
// Its output:
//   first draws after seed_seq{1, 2, 3}: 1831209241179374162 4398843623863442686
//   0x2a [[4, 3, 0, 5, 1, 2], [0, 2, 3, 4, 1, 5], [4, 1, 0, 5, 2, 3], [3, 4, 5, 2, 1, 0]]
//   0x123456789abcdef0 [[4, 5, 3, 0, 1, 2], [5, 2, 4, 0, 3, 1], [5, 2, 3, 1, 4, 0], [2, 0, 4, 5, 1, 3]]
// clang-format on
#include <algorithm>
#include <catch2/catch.hpp>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "haptel/study/design.hpp"
#include "test_env.hpp"

using Catch::Matchers::Contains;
using haptel::study::ConditionOrders;

namespace {

template <typename F>
std::string InvalidArgument(F&& f) {
  return haptel::test::WhatOf<std::invalid_argument>(std::forward<F>(f));
}

bool IsPermutation(std::vector<int> order, int k) {
  std::sort(order.begin(), order.end());
  std::vector<int> identity(k);
  std::iota(identity.begin(), identity.end(), 0);
  return order == identity;
}

}  // namespace

TEST_CASE("WilliamsRows: the square for 4 and the square with its mirror for 3",
          "[study][design]") {
  // Row 0 is 0, 1, k-1, 2, ...; each further row adds 1 (mod k).
  CHECK(haptel::study::WilliamsRows(4) ==
        std::vector<std::vector<int>>{{0, 1, 3, 2}, {1, 2, 0, 3}, {2, 3, 1, 0}, {3, 0, 2, 1}});
  CHECK(haptel::study::WilliamsRows(3) ==
        std::vector<std::vector<int>>{
            {0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}, {0, 2, 1}, {1, 0, 2}});
  CHECK(haptel::study::WilliamsRows(2) == std::vector<std::vector<int>>{{0, 1}, {1, 0}});
}

TEST_CASE("WilliamsRows: balanced for 2 to 8 conditions", "[study][design]") {
  for (int k = 2; k <= 8; ++k) {
    INFO("k = " << k);
    const auto rows = haptel::study::WilliamsRows(k);
    // Even k: one square; odd k: the square and its mirror, each count twice.
    const int rows_expected = k % 2 == 0 ? k : 2 * k;
    const int each = rows_expected / k;
    REQUIRE(static_cast<int>(rows.size()) == rows_expected);
    std::map<std::pair<int, int>, int> position_counts;  // (position, condition)
    std::map<std::pair<int, int>, int> pair_counts;      // (first, second)
    for (const auto& row : rows) {
      REQUIRE(IsPermutation(row, k));
      for (int p = 0; p < k; ++p) {
        ++position_counts[{p, row[p]}];
        if (p > 0) ++pair_counts[{row[p - 1], row[p]}];
      }
    }
    for (int p = 0; p < k; ++p) {
      for (int c = 0; c < k; ++c) CHECK(position_counts[{p, c}] == each);
    }
    for (int a = 0; a < k; ++a) {
      for (int b = 0; b < k; ++b) CHECK(pair_counts[{a, b}] == (a == b ? 0 : each));
    }
    // The library's own check agrees.
    const auto balance = haptel::study::CheckBalance(rows, k);
    CHECK(balance.every_sequence_complete);
    CHECK(balance.positions_balanced);
    CHECK(balance.carry_over_balanced);
  }
}

TEST_CASE("BalancedLatinSquareOrders: participant i runs row i mod rows", "[study][design]") {
  const auto rows = haptel::study::WilliamsRows(4);
  const auto orders = haptel::study::BalancedLatinSquareOrders(4, 12);
  REQUIRE(orders.size() == 12);
  for (int i = 0; i < 12; ++i) CHECK(orders[i] == rows[i % 4]);
  CHECK(haptel::study::CheckBalance(orders, 4).carry_over_balanced);

  const auto odd = haptel::study::BalancedLatinSquareOrders(5, 10);
  const auto odd_rows = haptel::study::WilliamsRows(5);
  for (int i = 0; i < 10; ++i) CHECK(odd[i] == odd_rows[i]);
  const auto odd_balance = haptel::study::CheckBalance(odd, 5);
  CHECK(odd_balance.positions_balanced);
  CHECK(odd_balance.carry_over_balanced);
  // The first 5 rows alone (the square without its mirror) are not.
  const ConditionOrders square_only(odd.begin(), odd.begin() + 5);
  CHECK_FALSE(haptel::study::CheckBalance(square_only, 5).carry_over_balanced);
  CHECK(haptel::study::CheckBalance(square_only, 5).positions_balanced);
}

TEST_CASE("BalancedLatinSquareOrders: repetitions repeat each participant's row",
          "[study][design]") {
  const auto orders = haptel::study::BalancedLatinSquareOrders(4, 4, 2);
  REQUIRE(orders.size() == 4);
  CHECK(orders[1] == std::vector<int>{1, 2, 0, 3, 1, 2, 0, 3});
  const auto balance = haptel::study::CheckBalance(orders, 4);
  CHECK(balance.every_sequence_complete);
  CHECK(balance.positions_balanced);
  // Each pair of the square comes once per repetition, and the seams (row 0's
  // 2 then 0, row 1's 3 then 1, ...) add pairs the square does not balance.
  CHECK_FALSE(balance.carry_over_balanced);
  CHECK(balance.adjacent_pair_counts[0][1] == 2);
  CHECK(balance.adjacent_pair_counts[2][0] == 3);
}

TEST_CASE("BalancedLatinSquareOrders: refuses counts it cannot balance", "[study][design]") {
  using haptel::study::BalancedLatinSquareOrders;
  CHECK(InvalidArgument([] { BalancedLatinSquareOrders(4, 3); }) ==
        "a balanced Latin square of 4 conditions needs a multiple of 4 participants, got 3");
  CHECK(InvalidArgument([] { BalancedLatinSquareOrders(4, 6); }) ==
        "a balanced Latin square of 4 conditions needs a multiple of 4 participants, got 6");
  CHECK(InvalidArgument([] { BalancedLatinSquareOrders(3, 3); }) ==
        "a balanced Latin square of 3 conditions needs a multiple of 6 participants, got 3");
  CHECK(InvalidArgument([] { BalancedLatinSquareOrders(5, 5); }) ==
        "a balanced Latin square of 5 conditions needs a multiple of 10 participants, got 5");
  CHECK_THAT(InvalidArgument([] { BalancedLatinSquareOrders(1, 2); }),
             Contains("a balanced Latin square needs at least 2 conditions, got 1"));
  CHECK_THAT(InvalidArgument([] { BalancedLatinSquareOrders(4, 0); }),
             Contains("expected at least 1 participant, got 0"));
  CHECK_THAT(InvalidArgument([] { BalancedLatinSquareOrders(4, 4, 0); }),
             Contains("expected at least 1 repetition, got 0"));
}

TEST_CASE("RandomOrders: the documented shuffle, reproducible from the seed", "[study][design]") {
  using haptel::study::RandomOrders;
  // Pinned to the Python above: the same orders on every platform.
  CHECK(RandomOrders(6, 4, 42) ==
        ConditionOrders{
            {4, 3, 0, 5, 1, 2}, {0, 2, 3, 4, 1, 5}, {4, 1, 0, 5, 2, 3}, {3, 4, 5, 2, 1, 0}});
  CHECK(RandomOrders(6, 4, 0x123456789ABCDEF0u) ==
        ConditionOrders{
            {4, 5, 3, 0, 1, 2}, {5, 2, 4, 0, 3, 1}, {5, 2, 3, 1, 4, 0}, {2, 0, 4, 5, 1, 3}});
  const auto a = RandomOrders(5, 40, 7);
  CHECK(a == RandomOrders(5, 40, 7));
  CHECK(a != RandomOrders(5, 40, 8));
  for (const auto& order : a) CHECK(IsPermutation(order, 5));
  // Each participant shuffles on their own: more participants leave the
  // first ones' orders as they were, and the orders are not all one.
  const auto fewer = RandomOrders(5, 3, 7);
  CHECK(ConditionOrders(a.begin(), a.begin() + 3) == fewer);
  CHECK(std::any_of(a.begin(), a.end(), [&](const auto& order) { return order != a.front(); }));
  // Over many participants every condition reaches every position.
  const auto many = haptel::study::CheckBalance(RandomOrders(5, 400, 1), 5);
  for (const auto& position : many.position_counts) {
    for (int count : position) CHECK(count > 40);  // 80 expected
  }

  const auto repeated = RandomOrders(3, 2, 9, 3);
  for (std::size_t i = 0; i < repeated.size(); ++i) {
    const auto once = RandomOrders(3, 2, 9)[i];
    CHECK(repeated[i] == std::vector<int>{once[0], once[1], once[2], once[0], once[1], once[2],
                                          once[0], once[1], once[2]});
  }
  CHECK(RandomOrders(1, 2, 5) == ConditionOrders{{0}, {0}});

  CHECK_THAT(InvalidArgument([] { RandomOrders(0, 2, 1); }),
             Contains("a random order design: expected at least 1 condition, got 0"));
  CHECK_THAT(InvalidArgument([] { RandomOrders(3, 0, 1); }),
             Contains("expected at least 1 participant, got 0"));
  CHECK_THAT(InvalidArgument([] { RandomOrders(3, 2, 1, -1); }),
             Contains("expected at least 1 repetition, got -1"));
}

TEST_CASE("FixedOrders: everyone runs the given order", "[study][design]") {
  using haptel::study::FixedOrders;
  CHECK(FixedOrders({2, 0, 1}, 3) == ConditionOrders{{2, 0, 1}, {2, 0, 1}, {2, 0, 1}});
  CHECK(FixedOrders({1, 0}, 1, 2) == ConditionOrders{{1, 0, 1, 0}});
  const auto balance = haptel::study::CheckBalance(FixedOrders({2, 0, 1}, 3), 3);
  CHECK(balance.every_sequence_complete);
  CHECK_FALSE(balance.positions_balanced);
  CHECK_FALSE(balance.carry_over_balanced);
  CHECK(balance.position_counts[0] == std::vector<int>{0, 0, 3});

  CHECK_THAT(InvalidArgument([] {
               FixedOrders({0, 1, 1}, 2);
             }),
             Contains("expected each of the conditions 0..2 exactly once, got 0, 1, 1"));
  CHECK_THAT(InvalidArgument([] {
               FixedOrders({0, 3}, 2);
             }),
             Contains("expected each of the conditions 0..1 exactly once, got 0, 3"));
  CHECK_THAT(InvalidArgument([] { FixedOrders({}, 2); }),
             Contains("a fixed order design: expected at least 1 condition, got 0"));
  CHECK_THAT(InvalidArgument([] {
               FixedOrders({0, 1}, 0);
             }),
             Contains("expected at least 1 participant, got 0"));
}

TEST_CASE("OrderDesign: the study file's names and MakeConditionOrders", "[study][design]") {
  using haptel::study::OrderDesign;
  using haptel::study::OrderDesignKind;
  using haptel::study::ParseOrderDesignKind;
  for (auto kind :
       {OrderDesignKind::kBalancedLatinSquare, OrderDesignKind::kRandom, OrderDesignKind::kFixed}) {
    CHECK(ParseOrderDesignKind(haptel::study::OrderDesignName(kind)) == kind);
  }
  CHECK(haptel::study::OrderDesignName(OrderDesignKind::kBalancedLatinSquare) ==
        "balanced-latin-square");
  CHECK(InvalidArgument([] { ParseOrderDesignKind("latin"); }) ==
        "order design: expected balanced-latin-square, random or fixed, got 'latin'");

  OrderDesign design;
  design.conditions = 4;
  design.participants = 8;
  design.repetitions = 2;
  CHECK(haptel::study::MakeConditionOrders(design) ==
        haptel::study::BalancedLatinSquareOrders(4, 8, 2));
  design.participants = 5;
  CHECK_THAT(InvalidArgument([&] { haptel::study::MakeConditionOrders(design); }),
             Contains("needs a multiple of 4 participants, got 5"));
  design.kind = OrderDesignKind::kRandom;
  design.seed = 99;
  CHECK(haptel::study::MakeConditionOrders(design) == haptel::study::RandomOrders(4, 5, 99, 2));
  design.kind = OrderDesignKind::kFixed;
  design.fixed_order = {3, 1, 0, 2};
  CHECK(haptel::study::MakeConditionOrders(design) ==
        haptel::study::FixedOrders({3, 1, 0, 2}, 5, 2));
  design.fixed_order = {1, 0, 2};
  CHECK(InvalidArgument([&] { haptel::study::MakeConditionOrders(design); }) ==
        "a fixed order design of 4 conditions: expected an order of 4 conditions, got 3");
}

TEST_CASE("CheckBalance: counts, and refuses orders it cannot count", "[study][design]") {
  using haptel::study::CheckBalance;
  // A cyclic Latin square balances positions but not carry-over: 1 always follows 0.
  const ConditionOrders cyclic = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}};
  const auto balance = CheckBalance(cyclic, 3);
  CHECK(balance.positions_balanced);
  CHECK_FALSE(balance.carry_over_balanced);
  CHECK(balance.adjacent_pair_counts[0][1] == 2);
  CHECK(balance.adjacent_pair_counts[1][0] == 0);
  // A condition run twice in a row is carry-over of itself; a sequence
  // without condition 2 is incomplete.
  const auto doubled = CheckBalance({{0, 0, 1}, {1, 1, 0}}, 2);
  CHECK_FALSE(doubled.carry_over_balanced);
  CHECK_FALSE(CheckBalance({{0, 1}, {1, 0}}, 3).every_sequence_complete);

  CHECK_THAT(InvalidArgument([] { CheckBalance({}, 3); }),
             Contains("expected at least 1 participant, got none"));
  CHECK_THAT(InvalidArgument([] {
               CheckBalance({{0, 1}}, 0);
             }),
             Contains("expected at least 1 condition, got 0"));
  CHECK_THAT(InvalidArgument([] { CheckBalance({{}}, 2); }),
             Contains("expected at least 1 position, got an empty order"));
  CHECK_THAT(InvalidArgument([] {
               CheckBalance({{0, 1}, {1}}, 2);
             }),
             Contains("expected every participant to have 2 positions (as participant 0 has), "
                      "participant 1 has 1"));
  CHECK_THAT(InvalidArgument([] {
               CheckBalance({{0, 1}, {1, 2}}, 2);
             }),
             Contains("expected conditions 0..1, participant 1 has 2 at position 2"));
  CHECK_THAT(InvalidArgument([] {
               CheckBalance({{-1, 1}}, 2);
             }),
             Contains("participant 0 has -1 at position 1"));
}
