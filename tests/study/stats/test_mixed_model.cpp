// The mixed model against R's lme4 1.1-31 and lmerTest 3.1-3 (Debian 12's
// r-cran-lme4, r-cran-lmertest) on fixed data sets: the values below are what
// tests/study/stats/lme4_reference.R prints, the data sets are the ones it
// holds. Estimates and standard errors match to 1e-4 (in fact ~1e-7); the
// Satterthwaite df, which lmerTest takes from a finite-difference Hessian, to
// 1e-3 relative, and the p-values and intervals that follow from them to 1e-5.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "haptel/study/mixed_model.hpp"
#include "haptel/study/statistics.hpp"

namespace haptel::study {
namespace {

using Catch::Matchers::Contains;

/// One trial of a data set: participant (1-based), condition (0 = the
/// reference), position (1-based), lap time in s.
struct Lap {
  int participant;
  int condition;
  int position;
  double lap_time_s;
};

// 4 conditions x 8 participants in the balanced Latin square's orders.
const std::vector<Lap> kBalanced = {
    {1, 0, 1, 113.51}, {1, 1, 2, 100.92}, {1, 3, 3, 48.99}, {1, 2, 4, 74.44}, {2, 1, 1, 105.82},
    {2, 2, 2, 70.27},  {2, 0, 3, 63.68},  {2, 3, 4, 41.47}, {3, 2, 1, 40.29}, {3, 3, 2, 30.67},
    {3, 1, 3, 55.06},  {3, 0, 4, 47.46},  {4, 3, 1, 29.48}, {4, 0, 2, 37.51}, {4, 2, 3, 39.78},
    {4, 1, 4, 45.81},  {5, 0, 1, 33.64},  {5, 1, 2, 46.47}, {5, 3, 3, 27.83}, {5, 2, 4, 42.35},
    {6, 1, 1, 86.39},  {6, 2, 2, 60.50},  {6, 0, 3, 57.69}, {6, 3, 4, 35.46}, {7, 2, 1, 71.43},
    {7, 3, 2, 33.67},  {7, 1, 3, 61.43},  {7, 0, 4, 59.86}, {8, 3, 1, 57.76}, {8, 0, 2, 78.83},
    {8, 2, 3, 65.04},  {8, 1, 4, 85.67}};

// Other draws without participant variance: REML's lands on 0.
const std::vector<Lap> kSingular = {
    {1, 0, 1, 54.62}, {1, 1, 2, 68.85}, {1, 3, 3, 34.43}, {1, 2, 4, 64.30}, {2, 1, 1, 73.24},
    {2, 2, 2, 48.49}, {2, 0, 3, 59.59}, {2, 3, 4, 41.89}, {3, 2, 1, 62.22}, {3, 3, 2, 38.80},
    {3, 1, 3, 80.73}, {3, 0, 4, 56.42}, {4, 3, 1, 38.52}, {4, 0, 2, 41.35}, {4, 2, 3, 62.37},
    {4, 1, 4, 61.41}, {5, 0, 1, 59.85}, {5, 1, 2, 77.16}, {5, 3, 3, 44.15}, {5, 2, 4, 55.34},
    {6, 1, 1, 80.01}, {6, 2, 2, 61.66}, {6, 0, 3, 56.01}, {6, 3, 4, 27.83}, {7, 2, 1, 62.63},
    {7, 3, 2, 40.28}, {7, 1, 3, 62.86}, {7, 0, 4, 42.68}, {8, 3, 1, 39.35}, {8, 0, 2, 61.38},
    {8, 2, 3, 64.60}, {8, 1, 4, 60.88}};

/// kBalanced without participant 3's trial at position 2.
std::vector<Lap> Missing() {
  std::vector<Lap> laps;
  for (const Lap& lap : kBalanced) {
    if (!(lap.participant == 3 && lap.position == 2)) laps.push_back(lap);
  }
  return laps;
}

std::vector<MixedModelObservation> LogLaps(const std::vector<Lap>& laps) {
  std::vector<MixedModelObservation> out;
  for (const Lap& lap : laps) {
    out.push_back({lap.participant, lap.condition, static_cast<double>(lap.position),
                   std::log(lap.lap_time_s)});
  }
  return out;
}

/// What lme4_reference.R prints for one data set. Terms: (Intercept),
/// condition1, condition2, condition3, position.
struct Reference {
  std::array<double, 5> estimate, standard_error, degrees_of_freedom, p_value, ci_low, ci_high;
  double participant_variance, residual_variance, reml_criterion;
  std::array<double, 4> mean_estimate, mean_standard_error, mean_degrees_of_freedom;
  double ml_deviance_full, ml_deviance_reduced, lrt_chi_square;
  int lrt_degrees_of_freedom;
  double lrt_p_value;
  double f;  ///< lmerTest's anova(fit): type III, Satterthwaite's F
  double f_denominator_df;
  double f_p_value;
};

// clang-format off
const Reference kBalancedReference{
  .estimate = {4.172512651, 0.1968394182, -0.02077749327, -0.4386688746, -0.04898715447},
  .standard_error = {0.1229400333, 0.06436647928, 0.06436647928, 0.06436647928, 0.02035446795},
  .degrees_of_freedom = {12.6534762, 20.00000007, 20.00000006, 20.00000006, 20.00000006},
  .p_value = {8.29763514e-14, 0.006206591113, 0.7501971768, 1.262338317e-06, 0.02588090972},
  .ci_low = {3.906175583, 0.06257329517, -0.1550436162, -0.5729349976, -0.09144583059},
  .ci_high = {4.438849718, 0.3311055411, 0.1134886297, -0.3044027516, -0.006528478351},
  .participant_variance = 0.08362662138,
  .residual_variance = 0.01657217462,
  .reml_criterion = -0.6984927856,
  .mean_estimate = {4.050044765, 4.246884183, 4.029267271, 3.61137589},
  .mean_standard_error = {0.111914474, 0.111914474, 0.111914474, 0.111914474},
  .mean_degrees_of_freedom = {9.05934065, 9.05934065, 9.05934065, 9.05934065},
  .ml_deviance_full = -21.40658742,
  .ml_deviance_reduced = 22.28231675,
  .lrt_chi_square = 43.68890417,
  .lrt_degrees_of_freedom = 3,
  .lrt_p_value = 1.757197026e-09,
  .f = 34.49432473,
  .f_denominator_df = 20.00000006,
  .f_p_value = 4.244697639e-08,
};
const Reference kMissingReference{
  .estimate = {4.17188868, 0.1968394182, -0.02077749327, -0.4411647575, -0.04873756619},
  .standard_error = {0.124149269, 0.06593712152, 0.06593712152, 0.06898506666, 0.02094952872},
  .degrees_of_freedom = {12.8593516, 19.00765024, 19.00765024, 19.06126364, 19.01346272},
  .p_value = {6.500623191e-14, 0.007603458977, 0.7561107999, 3.86106028e-06, 0.03120355181},
  .ci_low = {3.903381985, 0.05883519612, -0.1587817153, -0.5855207585, -0.09258333248},
  .ci_high = {4.440395375, 0.3348436402, 0.1172267288, -0.2968087564, -0.004891799896},
  .participant_variance = 0.08396937433,
  .residual_variance = 0.01739081598,
  .reml_criterion = 1.108958451,
  .mean_estimate = {4.049258675, 4.246098093, 4.028481181, 3.608093917},
  .mean_standard_error = {0.1125617074, 0.1125617074, 0.1125617074, 0.1143680324},
  .mean_degrees_of_freedom = {9.115837565, 9.115837564, 9.115837564, 9.661285269},
  .ml_deviance_full = -19.27550449,
  .ml_deviance_reduced = 20.1686589,
  .lrt_chi_square = 39.44416339,
  .lrt_degrees_of_freedom = 3,
  .lrt_p_value = 1.397524543e-08,
  .f = 29.58658543,
  .f_denominator_df = 19.03329692,
  .f_p_value = 2.257590159e-07,
};
const Reference kSingularReference{
  .estimate = {4.067209377, 0.2726540344, 0.1147872671, -0.3456672976, -0.0353352423},
  .standard_error = {0.06656906703, 0.06276191828, 0.06276191828, 0.06276191828, 0.01984706121},
  .degrees_of_freedom = {27, 27, 27, 27, 27},
  .p_value = {1.746633395e-30, 0.0001770723333, 0.07847645434, 7.814004849e-06, 0.08627151075},
  .ci_low = {3.930620934, 0.1438772152, -0.0139895521, -0.4744441168, -0.07605804815},
  .ci_high = {4.20379782, 0.4014308536, 0.2435640863, -0.2168904784, 0.005387563552},
  .participant_variance = 1.817419968e-25,
  .residual_variance = 0.01575623355,
  .reml_criterion = -23.43469229,
  .mean_estimate = {3.978871271, 4.251525306, 4.093658539, 3.633203974},
  .mean_standard_error = {0.04437937802, 0.04437937802, 0.04437937802, 0.04437937802},
  .mean_degrees_of_freedom = {27, 27, 27, 27},
  .ml_deviance_full = -47.44131781,
  .ml_deviance_reduced = 3.312673127,
  .lrt_chi_square = 50.75399094,
  .lrt_degrees_of_freedom = 3,
  .lrt_p_value = 5.519544844e-11,
  .f = 34.96029298,
  .f_denominator_df = 27,
  .f_p_value = 1.924936596e-09,
};
// clang-format on

void CheckContrast(const MixedModelContrast& c, const Reference& r, size_t term) {
  CHECK(c.estimate == Approx(r.estimate[term]).margin(1e-4));
  CHECK(c.standard_error == Approx(r.standard_error[term]).margin(1e-4));
  // Tighter than the brief's 1e-4 where it holds: lme4's optimum to ~1e-7.
  CHECK(c.estimate == Approx(r.estimate[term]).margin(1e-6));
  CHECK(c.standard_error == Approx(r.standard_error[term]).margin(1e-6));
  CHECK(c.degrees_of_freedom == Approx(r.degrees_of_freedom[term]).epsilon(1e-3));
  CHECK(c.p_value == Approx(r.p_value[term]).epsilon(1e-3).margin(1e-9));
  CHECK(c.ci_low == Approx(r.ci_low[term]).margin(1e-5));
  CHECK(c.ci_high == Approx(r.ci_high[term]).margin(1e-5));
}

void CheckAgainstLme4(const MixedModelResult& fit, const Reference& r, int observations) {
  CHECK(fit.observations == observations);
  CHECK(fit.participants == 8);
  CHECK(fit.reference_condition == 0);
  REQUIRE(fit.conditions.size() == 4);
  CHECK(fit.conditions[0].reference);
  CHECK_FALSE(fit.conditions[0].effect.has_value());
  for (size_t c = 1; c < 4; ++c) {
    INFO("condition " << c);
    REQUIRE(fit.conditions[c].effect.has_value());
    CheckContrast(*fit.conditions[c].effect, r, c);
  }
  INFO("position");
  REQUIRE(fit.position.has_value());
  CheckContrast(*fit.position, r, 4);
  for (size_t c = 0; c < 4; ++c) {
    INFO("mean of condition " << c);
    REQUIRE(fit.conditions[c].mean.has_value());
    CHECK(fit.conditions[c].mean->estimate == Approx(r.mean_estimate[c]).margin(1e-6));
    CHECK(fit.conditions[c].mean->standard_error == Approx(r.mean_standard_error[c]).margin(1e-6));
    CHECK(fit.conditions[c].mean->degrees_of_freedom ==
          Approx(r.mean_degrees_of_freedom[c]).epsilon(1e-3));
  }
  CHECK(fit.participant_variance == Approx(r.participant_variance).margin(1e-6));
  CHECK(fit.residual_variance == Approx(r.residual_variance).margin(1e-6));
  CHECK(fit.reml_criterion == Approx(r.reml_criterion).margin(1e-6));
  CHECK(fit.condition_test.ml_deviance_full == Approx(r.ml_deviance_full).margin(1e-5));
  CHECK(fit.condition_test.ml_deviance_reduced == Approx(r.ml_deviance_reduced).margin(1e-5));
  CHECK(fit.condition_test.chi_square == Approx(r.lrt_chi_square).margin(1e-5));
  CHECK(fit.condition_test.degrees_of_freedom == r.lrt_degrees_of_freedom);
  CHECK(fit.condition_test.likelihood_ratio_p_value == Approx(r.lrt_p_value).epsilon(1e-4));
  CHECK(fit.condition_test.f == Approx(r.f).epsilon(1e-4));
  CHECK(fit.condition_test.denominator_df == Approx(r.f_denominator_df).epsilon(1e-3));
  CHECK(fit.condition_test.p_value == Approx(r.f_p_value).epsilon(1e-3));
}

}  // namespace

TEST_CASE("RegularizedIncompleteBeta and Student's t: R's pbeta, pt and qt", "[study][stats]") {
  CHECK(RegularizedIncompleteBeta(2.5, 0.5, 0.3) == Approx(0.018927124071945644).epsilon(1e-12));
  CHECK(RegularizedIncompleteBeta(10, 0.5, 0.9) == Approx(0.15164090963470997).epsilon(1e-12));
  CHECK(RegularizedIncompleteBeta(0.7, 3, 0.2) == Approx(0.62907406457226256).epsilon(1e-12));
  CHECK(RegularizedIncompleteBeta(50, 40, 0.55) == Approx(0.45479521086387015).epsilon(1e-11));
  CHECK(RegularizedIncompleteBeta(2, 3, 0.0) == 0.0);
  CHECK(RegularizedIncompleteBeta(2, 3, 1.0) == 1.0);
  CHECK(StudentTTwoSidedP(2.1, 3) == Approx(0.12656520254968454).epsilon(1e-12));
  CHECK(StudentTTwoSidedP(0.4, 20.5) == Approx(0.69329395132562333).epsilon(1e-12));
  CHECK(StudentTTwoSidedP(-3.3, 9.06) == Approx(0.0091469240812239727).epsilon(1e-11));
  CHECK(StudentTTwoSidedP(5, 120) == Approx(1.9781905804539661e-06).epsilon(1e-10));
  CHECK(StudentTTwoSidedP(0.0, 7) == Approx(1.0));
  CHECK(StudentTQuantile(0.975, 1) == Approx(12.706204736174694).epsilon(1e-10));
  CHECK(StudentTQuantile(0.975, 9.059) == Approx(2.259913303759419).epsilon(1e-10));
  CHECK(StudentTQuantile(0.025, 20) == Approx(-2.0859634472658648).epsilon(1e-10));
  CHECK(StudentTQuantile(0.975, 1e4) == Approx(1.9602012398906257).epsilon(1e-10));
  CHECK(StudentTQuantile(0.9, 2.5) == Approx(1.7302509288071761).epsilon(1e-10));
  CHECK_THROWS_AS(StudentTQuantile(1.0, 5), std::invalid_argument);
  CHECK_THROWS_AS(StudentTTwoSidedP(1.0, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(RegularizedIncompleteBeta(1.0, 1.0, 1.5), std::invalid_argument);
}

TEST_CASE("FitMixedModel: lme4 and lmerTest on a balanced Latin-square study", "[study][stats]") {
  const MixedModelResult fit = FitMixedModel(LogLaps(kBalanced), 4);
  CheckAgainstLme4(fit, kBalancedReference, 32);
  CHECK_FALSE(fit.boundary);
  CHECK(fit.mean_position == Approx(2.5));
  CHECK(fit.notes.empty());
  CHECK_THAT(fit.method, Contains("Satterthwaite"));
  CHECK_THAT(fit.method, Contains("likelihood-ratio"));
}

TEST_CASE("FitMixedModel: lme4 and lmerTest with a missing trial", "[study][stats]") {
  const MixedModelResult fit = FitMixedModel(LogLaps(Missing()), 4);
  CheckAgainstLme4(fit, kMissingReference, 31);
  CHECK(fit.mean_position == Approx(78.0 / 31.0));
}

TEST_CASE("FitMixedModel: no participant variance lands on the boundary, as lme4's singular fit",
          "[study][stats]") {
  const MixedModelResult fit = FitMixedModel(LogLaps(kSingular), 4);
  CheckAgainstLme4(fit, kSingularReference, 32);
  CHECK(fit.boundary);
  CHECK(fit.participant_variance == 0.0);
  REQUIRE(fit.notes.size() == 1);
  CHECK_THAT(fit.notes[0], Contains("boundary"));
}

TEST_CASE("FitMixedModel: the participants' order does not matter, nor their ids",
          "[study][stats]") {
  std::vector<MixedModelObservation> shuffled = LogLaps(kBalanced);
  std::reverse(shuffled.begin(), shuffled.end());
  for (MixedModelObservation& o : shuffled) o.participant = 100 - 7 * o.participant;
  const MixedModelResult fit = FitMixedModel(shuffled, 4);
  CHECK(fit.conditions[3].effect->estimate == Approx(kBalancedReference.estimate[3]).margin(1e-6));
  CHECK(fit.participant_variance == Approx(kBalancedReference.participant_variance).margin(1e-6));
}

TEST_CASE("FitMixedModel: a condition without trials is not estimable, the others still are",
          "[study][stats]") {
  // The balanced data without condition 2, declared with 4 conditions.
  std::vector<MixedModelObservation> data;
  for (const MixedModelObservation& o : LogLaps(kBalanced)) {
    if (o.condition != 2) data.push_back(o);
  }
  const MixedModelResult fit = FitMixedModel(data, 4);
  CHECK_FALSE(fit.conditions[2].estimable);
  CHECK_FALSE(fit.conditions[2].effect.has_value());
  CHECK_FALSE(fit.conditions[2].mean.has_value());
  REQUIRE(fit.conditions[3].effect.has_value());
  CHECK(std::isfinite(fit.conditions[3].effect->p_value));
  CHECK(fit.condition_test.degrees_of_freedom == 2);

  SECTION("without the reference's trials, the first condition with trials is the reference") {
    std::vector<MixedModelObservation> no_reference;
    for (const MixedModelObservation& o : LogLaps(kBalanced)) {
      if (o.condition != 0) no_reference.push_back(o);
    }
    const MixedModelResult moved = FitMixedModel(no_reference, 4, 0);
    CHECK(moved.reference_condition == 1);
    CHECK(moved.conditions[1].reference);
    CHECK_FALSE(moved.conditions[1].effect.has_value());
    CHECK(moved.conditions[3].effect.has_value());
    REQUIRE_FALSE(moved.notes.empty());
    CHECK_THAT(moved.notes[0], Contains("no trials"));
  }
}

TEST_CASE(
    "FitMixedModel: a fixed order confounds position with condition; the position is left out",
    "[study][stats]") {
  std::vector<MixedModelObservation> data = LogLaps(kBalanced);
  for (MixedModelObservation& o : data) o.position = o.condition + 1.0;
  const MixedModelResult fit = FitMixedModel(data, 4);
  CHECK_FALSE(fit.position.has_value());
  REQUIRE(fit.conditions[1].effect.has_value());
  CHECK(std::isfinite(fit.conditions[1].effect->estimate));
  REQUIRE_FALSE(fit.notes.empty());
  CHECK_THAT(fit.notes[0], Contains("position is left out"));
}

TEST_CASE("FitMixedModel: refuses what it cannot fit, saying what it expected", "[study][stats]") {
  std::vector<MixedModelObservation> one_participant;
  for (const MixedModelObservation& o : LogLaps(kBalanced)) {
    if (o.participant == 1) one_participant.push_back(o);
  }
  CHECK_THROWS_WITH(FitMixedModel(one_participant, 4), Contains("at least 2 participants, got 1"));
  std::vector<MixedModelObservation> one_condition;
  for (const MixedModelObservation& o : LogLaps(kBalanced)) {
    if (o.condition == 1) one_condition.push_back(o);
  }
  CHECK_THROWS_WITH(FitMixedModel(one_condition, 4), Contains("at least 2 conditions, got 1"));
  std::vector<MixedModelObservation> capped = LogLaps(kBalanced);
  for (MixedModelObservation& o : capped) o.response = std::log(600.0);
  CHECK_THROWS_WITH(FitMixedModel(capped, 4), Contains("no variation"));
  std::vector<MixedModelObservation> bad = LogLaps(kBalanced);
  bad[5].response = std::nan("");
  CHECK_THROWS_WITH(FitMixedModel(bad, 4), Contains("observation 5"));
  CHECK_THROWS_WITH(FitMixedModel(LogLaps(kBalanced), 3), Contains("expected 0..2"));
  CHECK_THROWS_WITH(FitMixedModel({{1, 0, 1, 1.0}, {2, 1, 1, 2.0}}, 2),
                    Contains("more than one trial"));
}

namespace {

/// `datasets` seeded two-condition crossovers of `participants` (half in
/// order A, B, half in B, A: the balanced Latin square's two rows, the
/// pilot's design) with no condition effect: log lap = participant's speed
/// (SD 0.15) − 0.05 per trial of learning + trial noise (SD 0.05). Returns
/// the share whose condition test has p < 0.05, and `effect` added to
/// condition 1 turns it into a power.
double RejectionRate(int participants, int datasets, double effect, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  int rejected = 0;
  for (int d = 0; d < datasets; ++d) {
    std::vector<MixedModelObservation> observations;
    for (int p = 0; p < participants; ++p) {
      const double speed = 4.4 + 0.15 * normal(random);
      for (int position = 1; position <= 2; ++position) {
        const int condition = (p % 2 == 0) == (position == 1) ? 0 : 1;
        observations.push_back({p, condition, static_cast<double>(position),
                                speed - 0.05 * (position - 1) + (condition == 1 ? effect : 0.0) +
                                    0.05 * normal(random)});
      }
    }
    if (FitMixedModel(observations, 2).condition_test.p_value < 0.05) ++rejected;
  }
  return static_cast<double>(rejected) / datasets;
}

}  // namespace

TEST_CASE(
    "FitMixedModel: with no condition effect the condition test rejects in about alpha of the data "
    "sets",
    "[study][stats]") {
  // Binomial(400, 0.05): mean 20, SD 4.4; 0.10 is 40 rejections, 4.6 SD
  // above. Two participants leave no within-participant residual once
  // condition and position are fitted: the test must not find an effect in
  // noise there (it found one in every data set).
  for (const int participants : {2, 4, 8}) {
    INFO(participants << " participants");
    const double rate =
        RejectionRate(participants, 400, 0.0, 1000 + static_cast<std::uint64_t>(participants));
    INFO("rejection rate " << rate);
    CHECK(rate <= 0.10);
  }
}

TEST_CASE("FitMixedModel: a real condition effect is still found", "[study][stats]") {
  // 10 % longer laps in condition 1 against 5 % trial noise: the
  // within-participant difference has SD 0.07, so 8 participants find it
  // nearly always.
  const double rate = RejectionRate(8, 200, 0.10, 77);
  INFO("power " << rate);
  CHECK(rate >= 0.9);
}

}  // namespace haptel::study
