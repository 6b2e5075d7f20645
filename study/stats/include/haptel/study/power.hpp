#pragma once
/// @file The statistical power of a planned within-subject study, estimated
/// by Monte Carlo from a pool of simulated participants: the probability that
/// the study's planned analysis finds the condition effect at level α when it
/// is run with n participants.
///
/// The pool is data (each simulated participant's scored lap times, one per
/// trial, in their design's order); how it was simulated is the caller's
/// (`haptel study power` runs the study's synthetic drivers). For each
/// participant count n and each simulation:
/// - n participants are drawn from the pool *keeping the design balanced*:
///   n / rows from each order row (a row of the balanced Latin square; one row
///   for a random or fixed order), uniformly with replacement, so a count
///   larger than the pool can be drawn (a participant drawn twice enters the
///   analysis as two participants with the same laps: with replacement the
///   pool stands for the population it was drawn from, and the smaller the
///   pool per row, the more a large n overstates the power);
/// - the sample is analysed as `haptel study report` analyses a study:
///   Friedman's test on each participant's mean scored lap time per condition
///   (statistics.hpp; its exact p where that is cheap, the χ² one past it),
///   and the mixed model
///   log(lap time) ~ condition + position + (1 | participant) with the
///   Satterthwaite F test of the condition (mixed_model.hpp; not the χ²
///   likelihood-ratio test, which with few participants finds effects that
///   are not there);
/// - each test finds the effect when its p < α. An analysis that cannot be
///   done (every participant's laps tied, a fit refused) finds nothing and is
///   counted apart.
/// Power is the share of simulations finding the effect, reported with its
/// exact (Clopper–Pearson) 95 % binomial interval.
///
/// Every simulation draws from its own generator, seeded by (seed, n,
/// simulation index), so results repeat for the same seed whatever the order
/// they are computed in. The generator is std::mt19937_64 and the draws below
/// a bound are the unbiased rejection of design.hpp's RandomOrders, so they
/// are the same on every platform.
#include <atomic>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

namespace haptel::study {

/// One trial of a simulated participant as the study would score it.
struct PowerTrial {
  int condition = 0;        ///< 0..conditions − 1
  int position = 1;         ///< 1-based order within the participant
  double lap_time_s = 0.0;  ///< as scored (an unfinished lap: the cap); > 0
};

/// A simulated participant of the pool.
struct PowerParticipant {
  std::string id;  ///< for messages
  int row = 0;     ///< the design's order row it ran (0..rows − 1)
  /// Every condition at least once (with repetitions, more than once).
  std::vector<PowerTrial> trials;
};

struct PowerOptions {
  /// Each a positive multiple of the design's rows (a balanced design is
  /// balanced only over whole rows); analysed in the given order.
  std::vector<int> participant_counts = {4, 8, 12, 16};
  int simulations = 100;  ///< per count, ≥ 1
  double alpha = 0.05;    ///< each test's level
  /// `recommended_participants` is the smallest count whose mixed-model power
  /// reaches this.
  double target_power = 0.8;
  std::uint64_t seed = 1;
  /// Read before each simulation; once set, EstimatePower returns at once
  /// with `stopped` (a signal ends a long estimate promptly). May be null.
  const std::atomic<bool>* stop = nullptr;
};

/// A binomial proportion's confidence interval.
struct BinomialInterval {
  double low = 0.0;
  double high = 1.0;
};

/// The exact (Clopper–Pearson) interval of `successes` in `trials` (≥ 1) at
/// `confidence` (in (0, 1)): the Beta quantiles
/// [B(α/2; x, n − x + 1), B(1 − α/2; x + 1, n − x)], 0 for x = 0 and 1 for
/// x = n; found by bisection on RegularizedIncompleteBeta to 1e-12. As R's
/// `binom.test(x, n)$conf.int`. std::invalid_argument for counts out of range.
BinomialInterval ClopperPearsonInterval(int successes, int trials, double confidence = 0.95);

/// The power at one participant count.
struct PowerPoint {
  int participants = 0;
  int simulations = 0;
  int friedman_significant = 0;        ///< simulations whose Friedman p < α
  int lmm_significant = 0;             ///< simulations whose condition test (F) has p < α
  int friedman_not_analysed = 0;       ///< Friedman could not be computed (counted as not finding)
  int lmm_not_analysed = 0;            ///< the mixed model could not be fitted (likewise)
  double friedman_power = 0.0;         ///< friedman_significant / simulations
  double lmm_power = 0.0;              ///< lmm_significant / simulations
  BinomialInterval friedman_interval;  ///< 95 %, Clopper–Pearson
  BinomialInterval lmm_interval;
};

struct PowerResult {
  std::vector<PowerPoint> points;  ///< one per count, in PowerOptions order
  /// The smallest count whose mixed-model power reaches the target; nullopt
  /// when none does.
  std::optional<int> recommended_participants;
  int pool_participants = 0;
  int rows = 0;
  double alpha = 0.05;
  double target_power = 0.8;
  /// PowerOptions::stop was set: the points are incomplete, not a result.
  bool stopped = false;
};

/// Indices into `pool` of a balanced sample of `participants`: for each row
/// in turn (0, 1, ...), participants / rows of that row's pool participants,
/// uniformly with replacement. std::invalid_argument when `participants` is
/// not a positive multiple of `rows` or a row has no participant in the pool.
std::vector<size_t> DrawBalancedSample(const std::vector<PowerParticipant>& pool, int rows,
                                       int participants, std::mt19937_64& random);

/// The Monte Carlo estimate described above, for a design of `conditions`
/// conditions in `rows` order rows. std::invalid_argument (saying what was
/// expected) for an empty or unbalanced pool (a row without a participant, a
/// participant without every condition, a trial's condition out of range or
/// its lap time not > 0), a count that is not a positive multiple of `rows`,
/// fewer than 1 simulation, or α or the target outside (0, 1).
PowerResult EstimatePower(const std::vector<PowerParticipant>& pool, int conditions, int rows,
                          const PowerOptions& options);

}  // namespace haptel::study
