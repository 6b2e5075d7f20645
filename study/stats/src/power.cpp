#include "haptel/study/power.hpp"

#include <cmath>
#include <stdexcept>

#include "haptel/study/mixed_model.hpp"
#include "haptel/study/statistics.hpp"

namespace haptel::study {
namespace {

/// Uniform in 0..bound−1, as design.cpp draws: outputs below 2^64 mod bound
/// are rejected, so the accepted ones fall on whole cycles of `bound`.
std::uint64_t UniformBelow(std::mt19937_64& engine, std::uint64_t bound) {
  const std::uint64_t rejected_below = (std::uint64_t{0} - bound) % bound;  // 2^64 mod bound
  for (;;) {
    const std::uint64_t draw = engine();
    if (draw >= rejected_below) return draw % bound;
  }
}

/// The p with I_p(a, b) = `probability`, by bisection (I_p rises with p).
double BetaQuantile(double a, double b, double probability) {
  double low = 0.0;
  double high = 1.0;
  for (int i = 0; i < 200 && high - low > 1e-13; ++i) {
    const double mid = 0.5 * (low + high);
    (RegularizedIncompleteBeta(a, b, mid) < probability ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

/// Each pool participant's rows of the analysis: mean lap time per condition
/// (Friedman's row) and the trials (the mixed model's observations).
struct Prepared {
  std::vector<double> mean_lap_s;
  std::vector<PowerTrial> trials;
};

std::vector<Prepared> Prepare(const std::vector<PowerParticipant>& pool, int conditions, int rows) {
  if (conditions < 2)
    throw std::invalid_argument("power: expected at least 2 conditions, got " +
                                std::to_string(conditions));
  if (rows < 1)
    throw std::invalid_argument("power: expected at least 1 order row, got " +
                                std::to_string(rows));
  if (pool.empty())
    throw std::invalid_argument("power: the pool of simulated participants is empty");
  std::vector<int> per_row(static_cast<size_t>(rows), 0);
  std::vector<Prepared> prepared;
  for (const PowerParticipant& p : pool) {
    if (p.row < 0 || p.row >= rows) {
      throw std::invalid_argument("power: participant '" + p.id + "' has order row " +
                                  std::to_string(p.row) + ", expected 0.." +
                                  std::to_string(rows - 1));
    }
    ++per_row[static_cast<size_t>(p.row)];
    std::vector<double> sum(static_cast<size_t>(conditions), 0.0);
    std::vector<int> count(static_cast<size_t>(conditions), 0);
    for (const PowerTrial& t : p.trials) {
      if (t.condition < 0 || t.condition >= conditions) {
        throw std::invalid_argument("power: participant '" + p.id + "' has a trial of condition " +
                                    std::to_string(t.condition) + ", expected 0.." +
                                    std::to_string(conditions - 1));
      }
      if (!(t.lap_time_s > 0.0) || !std::isfinite(t.lap_time_s)) {
        throw std::invalid_argument("power: participant '" + p.id + "' has a lap time of " +
                                    std::to_string(t.lap_time_s) +
                                    " s, expected a finite time > 0");
      }
      sum[static_cast<size_t>(t.condition)] += t.lap_time_s;
      ++count[static_cast<size_t>(t.condition)];
    }
    Prepared row;
    for (int c = 0; c < conditions; ++c) {
      if (count[static_cast<size_t>(c)] == 0) {
        throw std::invalid_argument("power: participant '" + p.id + "' has no trial of condition " +
                                    std::to_string(c) +
                                    "; every pool participant needs every condition");
      }
      row.mean_lap_s.push_back(sum[static_cast<size_t>(c)] / count[static_cast<size_t>(c)]);
    }
    row.trials = p.trials;
    prepared.push_back(std::move(row));
  }
  for (int r = 0; r < rows; ++r) {
    if (per_row[static_cast<size_t>(r)] == 0) {
      throw std::invalid_argument("power: the pool has no participant in order row " +
                                  std::to_string(r) + " of " + std::to_string(rows) +
                                  "; a balanced draw needs every row");
    }
  }
  return prepared;
}

void CheckCount(int participants, int rows) {
  if (participants < 1 || participants % rows != 0) {
    throw std::invalid_argument(
        "power: expected a participant count that is a positive multiple of the design's " +
        std::to_string(rows) + " order rows (a balanced design is balanced only over " +
        "whole rows), got " + std::to_string(participants));
  }
}

}  // namespace

BinomialInterval ClopperPearsonInterval(int successes, int trials, double confidence) {
  if (trials < 1 || successes < 0 || successes > trials) {
    throw std::invalid_argument(
        "binomial interval: expected 0 <= successes <= trials and trials >= 1, got " +
        std::to_string(successes) + " of " + std::to_string(trials));
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("binomial interval: expected a confidence in (0, 1)");
  }
  const double tail = (1.0 - confidence) / 2.0;
  const double x = successes;
  const double n = trials;
  BinomialInterval interval;
  interval.low = successes == 0 ? 0.0 : BetaQuantile(x, n - x + 1.0, tail);
  interval.high = successes == trials ? 1.0 : BetaQuantile(x + 1.0, n - x, 1.0 - tail);
  return interval;
}

std::vector<size_t> DrawBalancedSample(const std::vector<PowerParticipant>& pool, int rows,
                                       int participants, std::mt19937_64& random) {
  CheckCount(participants, rows);
  std::vector<std::vector<size_t>> by_row(static_cast<size_t>(rows));
  for (size_t i = 0; i < pool.size(); ++i) {
    if (pool[i].row >= 0 && pool[i].row < rows)
      by_row[static_cast<size_t>(pool[i].row)].push_back(i);
  }
  std::vector<size_t> sample;
  for (int r = 0; r < rows; ++r) {
    const std::vector<size_t>& members = by_row[static_cast<size_t>(r)];
    if (members.empty()) {
      throw std::invalid_argument("power: the pool has no participant in order row " +
                                  std::to_string(r));
    }
    for (int i = 0; i < participants / rows; ++i) {
      sample.push_back(members[UniformBelow(random, members.size())]);
    }
  }
  return sample;
}

PowerResult EstimatePower(const std::vector<PowerParticipant>& pool, int conditions, int rows,
                          const PowerOptions& options) {
  const std::vector<Prepared> prepared = Prepare(pool, conditions, rows);
  if (options.simulations < 1) {
    throw std::invalid_argument("power: expected at least 1 simulation, got " +
                                std::to_string(options.simulations));
  }
  if (!(options.alpha > 0.0 && options.alpha < 1.0) ||
      !(options.target_power > 0.0 && options.target_power < 1.0)) {
    throw std::invalid_argument("power: expected alpha and the target power in (0, 1)");
  }
  if (options.participant_counts.empty())
    throw std::invalid_argument("power: expected at least one participant count");
  for (const int n : options.participant_counts) CheckCount(n, rows);

  PowerResult result;
  result.pool_participants = static_cast<int>(pool.size());
  result.rows = rows;
  result.alpha = options.alpha;
  result.target_power = options.target_power;
  for (const int n : options.participant_counts) {
    PowerPoint point;
    point.participants = n;
    point.simulations = options.simulations;
    for (int s = 0; s < options.simulations; ++s) {
      if (options.stop != nullptr && options.stop->load()) {
        result.stopped = true;
        return result;
      }
      std::seed_seq seeds{static_cast<std::uint32_t>(options.seed & 0xffffffffu),
                          static_cast<std::uint32_t>(options.seed >> 32),
                          static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(s)};
      std::mt19937_64 random(seeds);
      const std::vector<size_t> sample = DrawBalancedSample(pool, rows, n, random);
      BlockMatrix matrix;
      std::vector<MixedModelObservation> observations;
      for (size_t i = 0; i < sample.size(); ++i) {
        const Prepared& p = prepared[sample[i]];
        matrix.push_back(p.mean_lap_s);
        // A participant drawn twice is two participants with the same laps.
        for (const PowerTrial& t : p.trials) {
          observations.push_back({static_cast<int>(i), t.condition, static_cast<double>(t.position),
                                  std::log(t.lap_time_s)});
        }
      }
      try {
        if (FriedmanTest(matrix).p_value < options.alpha) ++point.friedman_significant;
      } catch (const std::invalid_argument&) {
        ++point.friedman_not_analysed;  // every row tied: no ranking to test
      }
      try {
        if (FitMixedModel(observations, conditions, 0).condition_test.p_value < options.alpha) {
          ++point.lmm_significant;
        }
      } catch (const std::invalid_argument&) {
        ++point.lmm_not_analysed;
      }
    }
    point.friedman_power = static_cast<double>(point.friedman_significant) / options.simulations;
    point.lmm_power = static_cast<double>(point.lmm_significant) / options.simulations;
    point.friedman_interval =
        ClopperPearsonInterval(point.friedman_significant, options.simulations);
    point.lmm_interval = ClopperPearsonInterval(point.lmm_significant, options.simulations);
    if (point.lmm_power >= options.target_power &&
        (!result.recommended_participants || n < *result.recommended_participants)) {
      result.recommended_participants = n;
    }
    result.points.push_back(point);
  }
  return result;
}

}  // namespace haptel::study
