#pragma once
/// @file Non-parametric statistics for a within-subject A/B study: every
/// participant runs every condition (mediator interface) once and the report
/// compares the conditions by their ranks within each participant.
///
/// The omnibus test is Friedman's, with Kendall's W as its effect size; the
/// pairs are compared either with Nemenyi's critical difference (Demšar 2006)
/// or with Wilcoxon signed-rank tests under Holm's step-down correction.
/// Every number here is the one SciPy 1.10 gives for the same data
/// (`scipy.stats.rankdata`, `friedmanchisquare`, `chi2.sf`, `wilcoxon`), up to
/// rounding; where SciPy has no function (Kendall's W, Nemenyi, Holm,
/// Friedman's exact p) the doc comment gives the formula.
///
/// Errors in the input (too few rows or columns, ragged rows, NaN or infinite
/// values) throw std::invalid_argument with a message that says what was
/// expected and what was given.
#include <optional>
#include <string>
#include <vector>

namespace haptel::study {

/// Measurements of a within-subject design: one row per participant (block),
/// one column per condition (treatment), e.g. lap times in s. Lower is better:
/// rank 1 is the smallest value in a row.
using BlockMatrix = std::vector<std::vector<double>>;

/// Ranks of `values`, 1 for the smallest; tied values share the average of
/// the ranks they span (SciPy's `rankdata(method='average')`), so the ranks
/// always sum to n(n+1)/2. Ties are exact equality.
std::vector<double> Ranks(const std::vector<double>& values);

/// The regularized upper incomplete gamma function Q(a, x) = Γ(a, x)/Γ(a),
/// a > 0, x ≥ 0 (SciPy's `special.gammaincc`). Computed as in Numerical
/// Recipes (gser/gcf): the series of P = 1 − Q for x < a + 1, where it
/// converges fast, and the continued fraction of Q (modified Lentz) otherwise,
/// where the series would cancel. Relative accuracy about 1e-14 for a up to a
/// few hundred, far beyond the degrees of freedom of a study.
double RegularizedUpperGamma(double a, double x);

/// P(X ≥ chi_square) for X chi-square distributed with `degrees_of_freedom`
/// (≥ 1): Q(df/2, chi_square/2), SciPy's `chi2.sf`.
double ChiSquareSurvival(double chi_square, int degrees_of_freedom);

/// The regularized incomplete beta function I_x(a, b), a, b > 0,
/// 0 ≤ x ≤ 1 (SciPy's `special.betainc`, R's `pbeta`): the continued
/// fraction of Numerical Recipes (betacf, modified Lentz), taken directly for
/// x < (a + 1)/(a + b + 2) and through I_x(a, b) = 1 − I_{1−x}(b, a) above,
/// where it converges fast.
double RegularizedIncompleteBeta(double a, double b, double x);

/// P(|T| ≥ |t|) for T Student-t distributed with `degrees_of_freedom` > 0
/// (not necessarily an integer: Satterthwaite's df are not), R's
/// `2 * pt(-abs(t), df)`: I_{df/(df + t²)}(df/2, 1/2).
double StudentTTwoSidedP(double t, double degrees_of_freedom);

/// The t with P(T ≤ t) = `probability` (in (0, 1)) for `degrees_of_freedom`
/// > 0, R's `qt(probability, df)`, found by bisection on StudentTTwoSidedP
/// to about 1e-12 relative.
double StudentTQuantile(double probability, double degrees_of_freedom);

/// Where one condition stands over all participants.
struct ConditionRank {
  double rank_sum = 0.0;   ///< R_j: sum over participants of the condition's rank in their row
  double mean_rank = 0.0;  ///< R_j / N; 1 would be best in every row
};

/// Friedman's test and Kendall's W for a BlockMatrix.
///
/// Both are tie-corrected the same way, so that W = χ²_F / (N (k − 1))
/// exactly. With S = Σ_j (R_j − N(k + 1)/2)² and T = Σ over rows of Σ(t³ − t)
/// over the row's groups of t tied values:
///   χ²_F = 12 S (k − 1) / (N(k³ − k) − T),
///   W    = 12 S / (N²(k³ − k) − N T).
/// χ²_F is algebraically SciPy's `friedmanchisquare`: its uncorrected
/// 12/(Nk(k+1)) Σ R_j² − 3N(k+1) divided by c = 1 − T/(Nk(k² − 1)); the form
/// through S cannot come out negative by cancellation.
///
/// The p-value is exact when that is cheap, the χ² approximation otherwise.
/// The χ² (df k − 1) is a large-sample result and liberal with few
/// participants: with k = 2 and N = 4 all preferring one condition it gives
/// p = 0.046 where the exact test (then the two-sided sign test) gives 0.125.
/// Exact: under H0 every ordering of a participant's own ranks (midranks
/// included, so ties stay ties) is equally likely, independently per row, and
/// p = P(S ≥ S_obs) over that permutation distribution — the one tabulated
/// for Friedman's test (e.g. Hollander & Wolfe; k = 3, N = 3, χ²_F = 6 gives
/// 1/36). Given the rows' ties, χ²_F grows with S, so the same p holds for
/// χ²_F and W. It is computed by convolving the rows' distributions of rank
/// sums (a dynamic programme over the vector of partial rank sums, kept up to
/// the order of the conditions, which H0 leaves symmetric), and is given up
/// for the χ² when k > kFriedmanExactMaxConditions or the programme would take
/// more than kFriedmanExactMaxSteps steps.
struct FriedmanResult {
  int participants = 0;              ///< N, rows of the matrix
  int conditions = 0;                ///< k, columns of the matrix
  std::vector<ConditionRank> ranks;  ///< per condition, in column order
  double chi_square = 0.0;           ///< χ²_F, tie-corrected
  int degrees_of_freedom = 0;        ///< k − 1
  /// The exact p (FriedmanExactP) when p_exact, else p_value_asymptotic:
  /// the one to report.
  double p_value = 1.0;
  /// ChiSquareSurvival(chi_square, k − 1), SciPy's `friedmanchisquare` p;
  /// always computed, for comparison.
  double p_value_asymptotic = 1.0;
  /// Whether p_value is the exact permutation p (true) or the χ² one (false).
  bool p_exact = false;
  double kendall_w = 0.0;  ///< coefficient of concordance, 0..1, tie-corrected
};

/// Largest k for which FriedmanTest tries the exact p: each row has up to k!
/// orderings to convolve (720 at k = 6).
inline constexpr int kFriedmanExactMaxConditions = 6;

/// Most steps (one per reachable rank-sum vector and ordering of the next
/// row, summed over the rows) the exact p's dynamic programme may take; past
/// it FriedmanTest keeps the χ² p. It bounds the time of one call, which
/// EstimatePower makes thousands of times, and the memory (the vectors held
/// never outnumber the steps). Before each row the programme bounds the
/// steps still to come from below and gives up as soon as that bound passes
/// the limit, so giving up costs at most this many steps (about 5 ms
/// measured). The distribution depends only on how each row ties
/// (every untied N × k study shares one), so the last few dozen distributions
/// and refusals are remembered between calls: EstimatePower's draws of one
/// participant count cost one programme, not hundreds.
inline constexpr long kFriedmanExactMaxSteps = 200000;

/// Friedman's test on `values` (N ≥ 2 rows of k ≥ 2 finite values each).
/// SciPy refuses k = 2; the formula holds there too (it is then the
/// two-sided sign test's χ²). Throws std::invalid_argument when every row is
/// entirely tied: there is no ranking to test (SciPy returns NaN).
FriedmanResult FriedmanTest(const BlockMatrix& values);

/// The exact p of Friedman's test (see FriedmanResult), or nothing when
/// k > kFriedmanExactMaxConditions or the dynamic programme would take more
/// than `max_steps` steps. Same checks and throws as FriedmanTest.
std::optional<double> FriedmanExactP(const BlockMatrix& values,
                                     long max_steps = kFriedmanExactMaxSteps);

/// Kendall's W of `values`, as in FriedmanResult (same checks, same throws).
double KendallW(const BlockMatrix& values);

/// The Wilcoxon signed-rank test of paired samples x and y, two-sided, on the
/// differences d = x − y, as SciPy's `wilcoxon(x, y, zero_method='wilcox',
/// correction=False)`: zero differences are dropped, |d| get average ranks.
///
/// The p-value is exact (the null distribution of W+ enumerated over all
/// 2^n sign assignments) when n ≤ 25 and there are no zeros and no ties in
/// |d|; otherwise it is the normal approximation with the tie correction of
/// the variance and without continuity correction:
///   z = (T − n(n+1)/4) / sqrt((n(n+1)(2n+1) − ½ Σ(t³ − t)) / 24),
///   p = 2 (1 − Φ(|z|)).
/// SciPy 1.10's `method='auto'` differs in two places: it stays exact up to
/// n = 50, and it stays "exact" with ties (truncating W+ to an integer, which
/// is wrong for half ranks); Haptel's reference values therefore come from
/// SciPy with `method='exact'` or `method='approx'` as this rule says.
struct WilcoxonResult {
  int pairs_used = 0;              ///< n: pairs with a nonzero difference
  int zero_differences = 0;        ///< pairs dropped because x == y
  double rank_sum_positive = 0.0;  ///< W+: sum of the ranks of |d| where x > y
  double rank_sum_negative = 0.0;  ///< W−: where x < y
  double statistic = 0.0;          ///< T = min(W+, W−), what SciPy reports two-sided
  double p_value = 1.0;            ///< two-sided
  bool exact = false;              ///< p from the exact null distribution (see above)
  std::optional<double> z;         ///< the normal approximation's z, when it was used
};

/// Throws std::invalid_argument when x and y differ in length, are empty,
/// hold a non-finite value, or every difference is zero.
WilcoxonResult WilcoxonSignedRank(const std::vector<double>& x, const std::vector<double>& y);

/// Holm's step-down adjustment of a family of p-values, in their given order:
/// with p sorted ascending, adjusted p_(i) = max_{j ≤ i} min(1, (m − j + 1) p_(j)),
/// so the adjusted values keep the order of the raw ones and never exceed 1.
/// A hypothesis is rejected at family-wise level α when its adjusted p ≤ α.
/// Throws std::invalid_argument for a value outside [0, 1] or NaN.
std::vector<double> HolmAdjust(const std::vector<double>& p_values);

/// Nemenyi's critical value q_α (the studentized range statistic divided by
/// √2) for k conditions, from Demšar (2006), Table 5. Tabulated for
/// k = 2..10 and α = 0.05 or 0.10 only; anything else throws
/// std::invalid_argument.
double NemenyiCriticalValue(int conditions, double alpha);

/// Nemenyi's critical difference CD = q_α sqrt(k(k + 1) / (6N)): two mean ranks
/// further apart than this differ at level α.
double NemenyiCriticalDifference(int conditions, int participants, double alpha);

/// One pair of conditions compared after the omnibus test.
struct PairComparison {
  int condition_a = 0;  ///< column index in the BlockMatrix
  int condition_b = 0;  ///< column index, > condition_a
  /// Nemenyi: |mean rank a − mean rank b|; Wilcoxon: T = min(W+, W−).
  double statistic = 0.0;
  /// Nemenyi: the statistic is significant when it exceeds this.
  std::optional<double> critical_difference;
  /// Wilcoxon: the Holm-adjusted p; significant when ≤ alpha.
  std::optional<double> p_value;
  bool significant = false;
};

/// Every pair of conditions, (0,1), (0,2), ..., (k−2,k−1), under one method.
struct PostHocResult {
  /// What the report prints, e.g. "Nemenyi (Demšar 2006), alpha 0.05".
  std::string method;
  double alpha = 0.05;
  std::vector<PairComparison> pairs;
};

/// Nemenyi's test on a FriedmanResult's mean ranks, α = 0.05 or 0.10.
PostHocResult NemenyiPostHoc(const FriedmanResult& friedman, double alpha);

/// A Wilcoxon signed-rank test for every pair of columns, p-values adjusted
/// by HolmAdjust over the k(k − 1)/2 pairs, α in (0, 1). A pair whose
/// differences are all zero has T = 0 and raw p = 1 (no evidence of a
/// difference) instead of throwing.
PostHocResult WilcoxonHolmPostHoc(const BlockMatrix& values, double alpha);

/// How the pairs are compared after Friedman's test.
enum class PostHocMethod {
  kNemenyi,       ///< critical difference of mean ranks; α 0.05 or 0.10
  kWilcoxonHolm,  ///< pairwise signed-rank tests, Holm-adjusted
};

/// Everything the study report prints and writes to JSON.
struct WithinSubjectAnalysis {
  FriedmanResult friedman;  ///< N, k, ranks per condition, χ²_F, df, p, W
  PostHocResult post_hoc;
};

/// Friedman's test, Kendall's W and the chosen post-hoc comparison of `values`.
WithinSubjectAnalysis AnalyzeWithinSubject(const BlockMatrix& values, PostHocMethod method,
                                           double alpha);

}  // namespace haptel::study
