#pragma once
/// @file A linear mixed model for a repeated-measures study:
///
///   response ~ condition + position + (1 | participant)
///
/// fitted by restricted maximum likelihood (REML), as R's
/// `lme4::lmer(y ~ condition + position + (1 | participant))` fits it. The
/// conditions enter as treatment contrasts against a reference condition
/// (intercept = the reference), the position (the trial's 1-based order
/// within its participant) as one numeric slope — a linear learning trend —
/// and each participant as a random intercept, b_i ~ N(0, σ_b²), beside the
/// residual ε ~ N(0, σ²).
///
/// How it is fitted: with θ = σ_b/σ the REML criterion profiled over β and σ²
/// is a function of θ alone,
///   d(θ) = log|H| + log|X'H⁻¹X| + (n − p)(1 + log(2π q/(n − p))),
///   H = I + θ² Z Z',  q = (y − Xβ̂)' H⁻¹ (y − Xβ̂),
/// with β̂ the generalized least-squares estimate for that θ (closed form; H
/// is block-diagonal, one block I + θ² 1 1' per participant, so every sum
/// is a sum over participants). d is minimised over θ ∈ [0, ∞) by a
/// log-spaced scan that brackets the minimum and Brent's method inside the
/// bracket, θ = 0 (no participant variance: the boundary) included. This is
/// lme4's criterion (its `REMLcrit`), and the fit agrees with lme4 to 1e-6.
///
/// Inference:
/// - each fixed-effect contrast (a condition against the reference, the
///   position, a condition's mean) by a t test with Satterthwaite's degrees of
///   freedom, as R's lmerTest computes them: df = 2 (l'Cl)² / (g' A g), where
///   C = Var(β̂) = σ²(X'H⁻¹X)⁻¹, g the gradient of l'Cl in the variance
///   components (σ_b², σ²) and A their asymptotic covariance, the inverse of
///   the REML criterion's observed information (computed in closed form, not
///   by finite differences as lmerTest does). At the boundary σ_b² = 0 the
///   participant variance is fixed there and df = n − p, as lmerTest gives;
/// - the condition effect as a whole by Satterthwaite's F test of its
///   (conditions − 1) contrasts against the reference, as lmerTest's
///   `anova(model)` computes it: L'β̂ rotated to the eigenvectors of L'CL,
///   F = the mean of the rotated contrasts' t², its denominator df from their
///   Satterthwaite df ν_i as 2E/(E − q), E = Σ ν_i/(ν_i − 2) (ν_1 for one
///   contrast, where F = t²). This is the test's p. With few participants
///   it, and not a χ², is what holds the level: the residual variance is
///   estimated from few within-participant df, which the F distribution
///   carries and the χ² ignores;
/// - beside it, the likelihood-ratio test of the model against the one
///   without condition, both refitted by maximum likelihood (ML), χ² with
///   (conditions − 1) df — R's `anova(reduced, full)` — for comparison
///   only: it is liberal with few participants (0.2 at α = 0.05 with 4 in
///   a two-condition crossover), and with 2 participants × 2 trials no
///   within-participant residual is left, the full model's ML likelihood
///   grows without bound as σ² → 0, and χ² is huge whatever the data.
///
/// Edge cases give results or a clear refusal, never NaN: a condition with
/// no observation is left out of the design (its effect is not estimable);
/// when the reference has none, the first condition with data becomes the
/// reference; a position that is a function of the condition (every
/// participant ran the conditions in the same order) is left out and said
/// so. When no variation within participants is left once the fixed effects
/// are fitted (n = rank of [X Z]: e.g. 2 participants × 2 trials with
/// condition and position) the two variances cannot be told apart; the
/// participants' is set to 0 (ordinary least squares, conservative tests),
/// with a note. Too little data throws std::invalid_argument saying what was needed.
#include <optional>
#include <string>
#include <vector>

namespace haptel::study {

/// One trial as the model sees it.
struct MixedModelObservation {
  int participant = 0;    ///< the participant's index, any int; equal ints are one participant
  int condition = 0;      ///< 0..conditions − 1
  double position = 1.0;  ///< the trial's 1-based order within its participant
  double response = 0.0;  ///< e.g. log(lap time in s)
};

/// A linear combination l'β of the fixed effects with its t test.
struct MixedModelContrast {
  double estimate = 0.0;
  double standard_error = 0.0;
  double degrees_of_freedom = 0.0;  ///< Satterthwaite's
  double t = 0.0;
  double p_value = 1.0;  ///< two-sided, of estimate = 0
  double ci_low = 0.0;   ///< the 95 % confidence interval, estimate ± t(0.975, df) SE
  double ci_high = 0.0;
};

/// What the fit gives for one condition.
struct MixedModelCondition {
  bool reference = false;  ///< the condition the others are compared with
  bool estimable = false;  ///< false when it has no observation
  /// Against the reference (response scale: on log lap times, a log ratio);
  /// nullopt for the reference itself and for a condition without data.
  std::optional<MixedModelContrast> effect;
  /// Its estimated mean response at the data's mean position (the
  /// intercept + its effect + slope × mean position); nullopt without data.
  std::optional<MixedModelContrast> mean;
};

/// The test of the condition effect as a whole: Satterthwaite's F test
/// (its p is the test's), and the likelihood-ratio test for comparison.
struct MixedModelConditionTest {
  int degrees_of_freedom = 0;  ///< conditions with data − 1: F's numerator df, χ²'s df
  double f = 0.0;              ///< Satterthwaite's F (t² for two conditions)
  double denominator_df =
      0.0;               ///< F's denominator df, Satterthwaite's (the t test's for two conditions)
  double p_value = 1.0;  ///< of the F test: the condition test's p
  double ml_deviance_full = 0.0;     ///< −2 log L of the ML refit with condition
  double ml_deviance_reduced = 0.0;  ///< −2 log L of the ML refit without it
  double chi_square = 0.0;           ///< reduced − full (≥ 0)
  /// The χ² likelihood-ratio test's p: liberal with few participants (see
  /// the file's comment), so not the test's.
  double likelihood_ratio_p_value = 1.0;
};

struct MixedModelResult {
  /// What the report prints as the method, naming the fit and both tests.
  std::string method;
  int observations = 0;
  int participants = 0;
  int reference_condition = 0;
  /// One per condition, in the given order (also those without data).
  std::vector<MixedModelCondition> conditions;
  /// The slope per position (per trial of experience); nullopt when the
  /// position was left out (see notes).
  std::optional<MixedModelContrast> position;
  double mean_position = 0.0;         ///< where `mean` of each condition is taken
  double participant_variance = 0.0;  ///< σ_b², REML
  double residual_variance = 0.0;     ///< σ², REML
  /// σ_b² = 0: REML puts no variance between participants (lme4's
  /// "boundary (singular) fit"); the fit is then ordinary least squares.
  bool boundary = false;
  double reml_criterion = 0.0;  ///< d(θ̂), lme4's REMLcrit
  MixedModelConditionTest condition_test;
  /// Why something is missing or changed, one sentence each.
  std::vector<std::string> notes;
};

/// Fits the model to `observations`, with `conditions` conditions of which
/// `reference` (default the first) is the reference. Throws
/// std::invalid_argument, saying what it expected, when there are fewer than
/// 2 participants, fewer than 2 conditions with data, no participant with
/// more than one observation, no more observations than fixed effects plus
/// one, a non-finite response or position, a condition index out of range,
/// or no variation left to estimate a residual variance from.
MixedModelResult FitMixedModel(const std::vector<MixedModelObservation>& observations,
                               int conditions, int reference = 0);

}  // namespace haptel::study
