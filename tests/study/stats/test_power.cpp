// The power estimate's Monte Carlo core on synthetic pools whose effect is
// known: a large effect is found in (almost) every simulation at n = 8, no
// effect in about α of them; the balanced draw takes n / rows from each row;
// the binomial interval is R's binom.test.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "haptel/study/design.hpp"
#include "haptel/study/power.hpp"

using namespace haptel::study;

namespace {

/// `per_row` participants per Williams row of 4 conditions; participant p's
/// lap in condition c is base_p · exp(effect_c + ε), base_p ~ 20 s · exp(N(0, 0.3²))
/// (participants differ a lot), ε ~ N(0, noise²) per trial.
std::vector<PowerParticipant> SyntheticPool(int per_row, const std::vector<double>& log_effect,
                                            double noise, std::uint64_t seed) {
  const int k = static_cast<int>(log_effect.size());
  const std::vector<std::vector<int>> rows = WilliamsRows(k);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<PowerParticipant> pool;
  for (size_t r = 0; r < rows.size(); ++r) {
    for (int i = 0; i < per_row; ++i) {
      PowerParticipant p;
      p.id = std::to_string(r * 1000 + static_cast<size_t>(i));  // row · 1000 + index
      p.row = static_cast<int>(r);
      const double base_s = 20.0 * std::exp(0.3 * normal(random));
      for (size_t position = 0; position < rows[r].size(); ++position) {
        const int c = rows[r][position];
        p.trials.push_back(
            {c, static_cast<int>(position) + 1,
             base_s * std::exp(log_effect[static_cast<size_t>(c)] + noise * normal(random))});
      }
      pool.push_back(p);
    }
  }
  return pool;
}

}  // namespace

TEST_CASE("power: a large known effect is found at n = 8 by both tests", "[power]") {
  // Conditions 0..3 take 1, 1.22, 1.49, 1.82 times as long, trial noise 5 %.
  const auto pool = SyntheticPool(8, {0.0, 0.2, 0.4, 0.6}, 0.05, 7);
  PowerOptions options;
  options.participant_counts = {8};
  options.simulations = 100;
  options.seed = 3;
  const PowerResult result = EstimatePower(pool, 4, 4, options);
  REQUIRE(result.points.size() == 1);
  const PowerPoint& p = result.points[0];
  CHECK(p.participants == 8);
  CHECK(p.simulations == 100);
  CHECK(p.friedman_power >= 0.99);
  CHECK(p.lmm_power >= 0.99);
  CHECK(p.friedman_not_analysed == 0);
  CHECK(p.lmm_not_analysed == 0);
  REQUIRE(result.recommended_participants.has_value());
  CHECK(*result.recommended_participants == 8);
  CHECK(result.pool_participants == 32);
}

TEST_CASE("power: with no effect the tests find one in about alpha of the simulations", "[power]") {
  // A large pool, so its own chance differences between conditions are small
  // beside a sample's; 12 % trial noise; no condition effect at all.
  const auto pool = SyntheticPool(100, {0.0, 0.0, 0.0, 0.0}, 0.12, 11);
  PowerOptions options;
  options.participant_counts = {16};
  options.simulations = 600;
  options.seed = 5;
  const PowerResult result = EstimatePower(pool, 4, 4, options);
  const PowerPoint& p = result.points[0];
  INFO("friedman " << p.friedman_power << ", lmm " << p.lmm_power);
  // Binomial(600, 0.05): mean 30, sd 5.3; ±3.5 sd is 0.019..0.081. The
  // likelihood-ratio test's χ² is a little liberal with 16 participants
  // (0.045 measured here), so its upper bound allows 0.085.
  CHECK(p.friedman_power >= 0.019);
  CHECK(p.friedman_power <= 0.081);
  CHECK(p.lmm_power >= 0.019);
  CHECK(p.lmm_power <= 0.085);
  CHECK_FALSE(result.recommended_participants.has_value());
}

TEST_CASE("power: two identical conditions are not told apart with 2 or 4 participants",
          "[power]") {
  // The shared-control pilot's case: the same interface twice, one trial
  // each, the two orders of a balanced square. The mixed model found an
  // effect in every draw of 2 participants (power 1.0 of nothing).
  const auto pool = SyntheticPool(100, {0.0, 0.0}, 0.05, 13);
  PowerOptions options;
  options.participant_counts = {2, 4};
  options.simulations = 400;
  options.seed = 9;
  const PowerResult result = EstimatePower(pool, 2, 2, options);
  REQUIRE(result.points.size() == 2);
  for (const PowerPoint& p : result.points) {
    INFO(p.participants << " participants: lmm " << p.lmm_power << " (" << p.lmm_not_analysed
                        << " not analysed), friedman " << p.friedman_power);
    // Binomial(400, 0.05): 0.10 is 4.6 SD above alpha.
    CHECK(p.lmm_power <= 0.10);
    // Friedman's exact p is the sign test's here, never below 2/2^N: 0.5 with
    // 2 participants, 0.125 with 4, so it cannot reject at 0.05. (The χ²
    // p rejected whenever all 4 agreed, 2/16 = 0.125 of the draws.)
    CHECK(p.friedman_power == 0.0);
  }
  CHECK_FALSE(result.recommended_participants.has_value());
}

TEST_CASE("power: the same seed gives the same estimate, the counts in the order asked",
          "[power]") {
  const auto pool = SyntheticPool(2, {0.0, 0.05, 0.1, 0.15}, 0.1, 13);
  PowerOptions options;
  options.participant_counts = {12, 4};
  options.simulations = 40;
  options.seed = 9;
  const PowerResult a = EstimatePower(pool, 4, 4, options);
  const PowerResult b = EstimatePower(pool, 4, 4, options);
  REQUIRE(a.points.size() == 2);
  CHECK(a.points[0].participants == 12);
  CHECK(a.points[1].participants == 4);
  for (size_t i = 0; i < 2; ++i) {
    CHECK(a.points[i].friedman_significant == b.points[i].friedman_significant);
    CHECK(a.points[i].lmm_significant == b.points[i].lmm_significant);
  }
  // The recommendation is the smallest count reaching the target, whatever the order.
  if (a.points[0].lmm_power >= 0.8 && a.points[1].lmm_power >= 0.8)
    CHECK(*a.recommended_participants == 4);
}

TEST_CASE("power: the balanced draw takes participants / rows from each row", "[power]") {
  // Rows of unequal size in the pool: 1, 2, 3 and 6 participants.
  std::vector<PowerParticipant> pool;
  const int sizes[] = {1, 2, 3, 6};
  for (int r = 0; r < 4; ++r) {
    for (int i = 0; i < sizes[r]; ++i) pool.push_back({"p", r, {}});
  }
  std::mt19937_64 random(1);
  for (const int n : {4, 8, 16, 40}) {
    for (int repeat = 0; repeat < 20; ++repeat) {
      const std::vector<size_t> sample = DrawBalancedSample(pool, 4, n, random);
      REQUIRE(sample.size() == static_cast<size_t>(n));
      int per_row[4] = {0, 0, 0, 0};
      for (const size_t i : sample) {
        REQUIRE(i < pool.size());
        ++per_row[pool[i].row];
      }
      for (const int count : per_row) CHECK(count == n / 4);
    }
  }
  // With replacement: the single participant of row 0 fills its share.
  const std::vector<size_t> large = DrawBalancedSample(pool, 4, 40, random);
  CHECK(std::count(large.begin(), large.end(), size_t{0}) == 10);
  // Row 3's six are all drawn sometime: the draw is not stuck on one.
  std::set<size_t> seen;
  for (int repeat = 0; repeat < 50; ++repeat) {
    for (const size_t i : DrawBalancedSample(pool, 4, 4, random)) seen.insert(i);
  }
  CHECK(seen.size() == pool.size());
}

TEST_CASE("power: counts that cannot be balanced and broken pools are refused, saying why",
          "[power]") {
  const auto pool = SyntheticPool(2, {0.0, 0.1, 0.2, 0.3}, 0.1, 1);
  std::mt19937_64 random(1);
  CHECK_THROWS_WITH(DrawBalancedSample(pool, 4, 6, random),
                    Catch::Contains("positive multiple of the design's 4 order rows") &&
                        Catch::Contains("got 6"));
  CHECK_THROWS_WITH(DrawBalancedSample(pool, 4, 0, random), Catch::Contains("got 0"));
  PowerOptions options;
  options.participant_counts = {4};
  options.simulations = 0;
  CHECK_THROWS_WITH(EstimatePower(pool, 4, 4, options), Catch::Contains("at least 1 simulation"));
  options.simulations = 10;
  std::vector<PowerParticipant> missing_row(pool.begin(), pool.begin() + 6);  // rows 0..2 only
  CHECK_THROWS_WITH(EstimatePower(missing_row, 4, 4, options),
                    Catch::Contains("no participant in order row 3"));
  std::vector<PowerParticipant> missing_condition = pool;
  missing_condition[0].trials.pop_back();
  CHECK_THROWS_WITH(EstimatePower(missing_condition, 4, 4, options),
                    Catch::Contains("has no trial of condition"));
  CHECK_THROWS_WITH(EstimatePower({}, 4, 4, options), Catch::Contains("empty"));
}

TEST_CASE("power: Clopper-Pearson intervals are R's binom.test", "[power]") {
  // R 4.2: binom.test(5, 10)$conf.int, binom.test(0, 10), binom.test(80, 100), binom.test(100,
  // 100).
  const BinomialInterval half = ClopperPearsonInterval(5, 10);
  CHECK(half.low == Approx(0.1870860).margin(1e-6));
  CHECK(half.high == Approx(0.8129140).margin(1e-6));
  const BinomialInterval none = ClopperPearsonInterval(0, 10);
  CHECK(none.low == 0.0);
  CHECK(none.high == Approx(0.3084971).margin(1e-6));
  const BinomialInterval most = ClopperPearsonInterval(80, 100);
  CHECK(most.low == Approx(0.7081573).margin(1e-6));
  CHECK(most.high == Approx(0.8733444).margin(1e-6));
  const BinomialInterval all = ClopperPearsonInterval(100, 100);
  CHECK(all.low == Approx(0.9637833).margin(1e-6));
  CHECK(all.high == 1.0);
  CHECK_THROWS(ClopperPearsonInterval(11, 10));
}
