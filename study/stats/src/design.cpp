#include "haptel/study/design.hpp"

#include <algorithm>
#include <functional>
#include <numeric>
#include <random>
#include <stdexcept>
#include <utility>

namespace haptel::study {
namespace {

void RequireCounts(const std::string& design, int conditions, int min_conditions, int participants,
                   int repetitions) {
  if (conditions < min_conditions) {
    throw std::invalid_argument(design + ": expected at least " + std::to_string(min_conditions) +
                                " condition" + (min_conditions == 1 ? "" : "s") + ", got " +
                                std::to_string(conditions));
  }
  if (participants < 1) {
    throw std::invalid_argument(design + ": expected at least 1 participant, got " +
                                std::to_string(participants));
  }
  if (repetitions < 1) {
    throw std::invalid_argument(design + ": expected at least 1 repetition, got " +
                                std::to_string(repetitions));
  }
}

/// `sequence` run `repetitions` times in a row.
std::vector<int> Repeated(const std::vector<int>& sequence, int repetitions) {
  std::vector<int> out;
  out.reserve(sequence.size() * static_cast<std::size_t>(repetitions));
  for (int r = 0; r < repetitions; ++r) out.insert(out.end(), sequence.begin(), sequence.end());
  return out;
}

/// Uniform in 0..bound−1: outputs below 2^64 mod bound are rejected, so the
/// accepted ones fall on a whole number of cycles of `bound`.
std::uint64_t UniformBelow(std::mt19937_64& engine, std::uint64_t bound) {
  const std::uint64_t rejected_below = (std::uint64_t{0} - bound) % bound;  // 2^64 mod bound
  for (;;) {
    const std::uint64_t draw = engine();
    if (draw >= rejected_below) return draw % bound;
  }
}

}  // namespace

std::vector<std::vector<int>> WilliamsRows(int conditions) {
  if (conditions < 2) {
    throw std::invalid_argument("a balanced Latin square needs at least 2 conditions, got " +
                                std::to_string(conditions));
  }
  const int k = conditions;
  // 0, 1, k−1, 2, k−2, ...: the steps +1, −2, +3, −4, ... (mod k) between
  // neighbours are all different for even k, so shifting the row by 0..k−1
  // meets every ordered pair once.
  std::vector<int> first(k);
  for (int j = 0; j < k; ++j) first[j] = j % 2 == 1 ? (j + 1) / 2 : (k - j / 2) % k;
  std::vector<std::vector<int>> rows;
  for (int shift = 0; shift < k; ++shift) {
    std::vector<int> row(k);
    for (int j = 0; j < k; ++j) row[j] = (first[j] + shift) % k;
    rows.push_back(std::move(row));
  }
  if (k % 2 == 1) {
    // For odd k the steps repeat; the mirrored rows take the negated steps,
    // and together every nonzero step, hence every ordered pair, comes twice.
    for (int shift = 0; shift < k; ++shift) {
      rows.emplace_back(rows[shift].rbegin(), rows[shift].rend());
    }
  }
  return rows;
}

ConditionOrders BalancedLatinSquareOrders(int conditions, int participants, int repetitions) {
  const std::vector<std::vector<int>> rows = WilliamsRows(conditions);
  RequireCounts("a balanced Latin square", conditions, 2, participants, repetitions);
  const int row_count = static_cast<int>(rows.size());
  if (participants % row_count != 0) {
    throw std::invalid_argument("a balanced Latin square of " + std::to_string(conditions) +
                                " conditions needs a multiple of " + std::to_string(row_count) +
                                " participants, got " + std::to_string(participants));
  }
  ConditionOrders orders;
  for (int i = 0; i < participants; ++i)
    orders.push_back(Repeated(rows[i % row_count], repetitions));
  return orders;
}

ConditionOrders RandomOrders(int conditions, int participants, std::uint64_t seed,
                             int repetitions) {
  RequireCounts("a random order design", conditions, 1, participants, repetitions);
  ConditionOrders orders;
  for (int i = 0; i < participants; ++i) {
    std::seed_seq seeds{static_cast<std::uint32_t>(seed & 0xffffffffu),
                        static_cast<std::uint32_t>(seed >> 32), static_cast<std::uint32_t>(i)};
    std::mt19937_64 engine(seeds);
    std::vector<int> order(conditions);
    std::iota(order.begin(), order.end(), 0);
    for (int j = conditions - 1; j > 0; --j) {
      const auto pick = static_cast<int>(UniformBelow(engine, static_cast<std::uint64_t>(j) + 1));
      std::swap(order[j], order[pick]);
    }
    orders.push_back(Repeated(order, repetitions));
  }
  return orders;
}

ConditionOrders FixedOrders(const std::vector<int>& order, int participants, int repetitions) {
  const int k = static_cast<int>(order.size());
  RequireCounts("a fixed order design", k, 1, participants, repetitions);
  std::vector<int> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (int c = 0; c < k; ++c) {
    if (sorted[c] != c) {
      std::string given;
      for (int v : order) given += (given.empty() ? "" : ", ") + std::to_string(v);
      throw std::invalid_argument("a fixed order design: expected each of the conditions 0.." +
                                  std::to_string(k - 1) + " exactly once, got " + given);
    }
  }
  return ConditionOrders(static_cast<std::size_t>(participants), Repeated(order, repetitions));
}

std::string_view OrderDesignName(OrderDesignKind kind) {
  switch (kind) {
    case OrderDesignKind::kBalancedLatinSquare:
      return "balanced-latin-square";
    case OrderDesignKind::kRandom:
      return "random";
    case OrderDesignKind::kFixed:
      return "fixed";
  }
  throw std::invalid_argument("OrderDesignName: not an OrderDesignKind");
}

OrderDesignKind ParseOrderDesignKind(std::string_view name) {
  for (OrderDesignKind kind :
       {OrderDesignKind::kBalancedLatinSquare, OrderDesignKind::kRandom, OrderDesignKind::kFixed}) {
    if (name == OrderDesignName(kind)) return kind;
  }
  throw std::invalid_argument(
      "order design: expected balanced-latin-square, random or fixed, got '" + std::string(name) +
      "'");
}

ConditionOrders MakeConditionOrders(const OrderDesign& design) {
  switch (design.kind) {
    case OrderDesignKind::kBalancedLatinSquare:
      return BalancedLatinSquareOrders(design.conditions, design.participants, design.repetitions);
    case OrderDesignKind::kRandom:
      return RandomOrders(design.conditions, design.participants, design.seed, design.repetitions);
    case OrderDesignKind::kFixed:
      if (static_cast<int>(design.fixed_order.size()) != design.conditions) {
        throw std::invalid_argument("a fixed order design of " + std::to_string(design.conditions) +
                                    " conditions: expected an order of " +
                                    std::to_string(design.conditions) + " conditions, got " +
                                    std::to_string(design.fixed_order.size()));
      }
      return FixedOrders(design.fixed_order, design.participants, design.repetitions);
  }
  throw std::invalid_argument("MakeConditionOrders: not an OrderDesignKind");
}

DesignBalance CheckBalance(const ConditionOrders& orders, int conditions) {
  if (conditions < 1) {
    throw std::invalid_argument("design balance: expected at least 1 condition, got " +
                                std::to_string(conditions));
  }
  if (orders.empty()) {
    throw std::invalid_argument("design balance: expected at least 1 participant, got none");
  }
  const std::size_t length = orders.front().size();
  if (length == 0) {
    throw std::invalid_argument("design balance: expected at least 1 position, got an empty order");
  }
  const auto k = static_cast<std::size_t>(conditions);
  DesignBalance balance;
  balance.position_counts.assign(length, std::vector<int>(k, 0));
  balance.adjacent_pair_counts.assign(k, std::vector<int>(k, 0));
  balance.every_sequence_complete = length % k == 0;
  for (std::size_t i = 0; i < orders.size(); ++i) {
    const std::vector<int>& order = orders[i];
    if (order.size() != length) {
      throw std::invalid_argument("design balance: expected every participant to have " +
                                  std::to_string(length) +
                                  " positions (as participant 0 has), participant " +
                                  std::to_string(i) + " has " + std::to_string(order.size()));
    }
    std::vector<std::size_t> runs(k, 0);
    for (std::size_t p = 0; p < length; ++p) {
      if (order[p] < 0 || order[p] >= conditions) {
        throw std::invalid_argument("design balance: expected conditions 0.." +
                                    std::to_string(conditions - 1) + ", participant " +
                                    std::to_string(i) + " has " + std::to_string(order[p]) +
                                    " at position " + std::to_string(p + 1));
      }
      ++runs[order[p]];
      ++balance.position_counts[p][order[p]];
      if (p > 0) ++balance.adjacent_pair_counts[order[p - 1]][order[p]];
    }
    for (std::size_t c = 0; c < k; ++c) {
      if (runs[c] != length / k) balance.every_sequence_complete = false;
    }
  }
  const auto all_equal = [](const std::vector<int>& counts) {
    return std::adjacent_find(counts.begin(), counts.end(), std::not_equal_to<>()) == counts.end();
  };
  balance.positions_balanced =
      std::all_of(balance.position_counts.begin(), balance.position_counts.end(), all_equal);
  std::vector<int> distinct_pairs;
  bool self_follows = false;
  for (std::size_t a = 0; a < k; ++a) {
    for (std::size_t b = 0; b < k; ++b) {
      if (a == b) {
        self_follows = self_follows || balance.adjacent_pair_counts[a][b] > 0;
      } else {
        distinct_pairs.push_back(balance.adjacent_pair_counts[a][b]);
      }
    }
  }
  balance.carry_over_balanced = !self_follows && all_equal(distinct_pairs);
  return balance;
}

}  // namespace haptel::study
