# Reference values for tests/study/stats/test_mixed_model.cpp: R's lme4 (and
# lmerTest for Satterthwaite's degrees of freedom) on fixed data sets. Computed
# once with Debian 12's r-base-core 4.2.2, r-cran-lme4 1.1-31 and
# r-cran-lmertest 3.1-3; the product does not need R. Re-run with
#   Rscript tests/study/stats/lme4_reference.R
# and paste what it prints into the test.
#
# Data: 4 conditions (0 is the reference) x 8 participants, each condition's
# position from the balanced Latin square Haptel plans for k = 4 (Williams
# rows 0 1 3 2 / 1 2 0 3 / 2 3 1 0 / 3 0 2 1, participants 1-4 and 5-8), lap
# times in s drawn once from log(lap) = log(60) + condition + learning +
# participant + noise and rounded to 0.01 s:
#   balanced - every trial;
#   missing  - balanced without participant 3's position-2 trial;
#   singular - other draws with no participant variance, where REML's
#              participant variance lands on its boundary, 0.
suppressPackageStartupMessages({ library(lme4); library(lmerTest) })

rows <- function(v) data.frame(participant = factor(v[c(TRUE, FALSE, FALSE, FALSE)]),
                               condition = factor(v[c(FALSE, TRUE, FALSE, FALSE)], levels = 0:3),
                               position = v[c(FALSE, FALSE, TRUE, FALSE)],
                               lap = v[c(FALSE, FALSE, FALSE, TRUE)])
balanced <- rows(c(
  1, 0, 1, 113.51,  1, 1, 2, 100.92,  1, 3, 3, 48.99,  1, 2, 4, 74.44,
  2, 1, 1, 105.82,  2, 2, 2, 70.27,   2, 0, 3, 63.68,  2, 3, 4, 41.47,
  3, 2, 1, 40.29,   3, 3, 2, 30.67,   3, 1, 3, 55.06,  3, 0, 4, 47.46,
  4, 3, 1, 29.48,   4, 0, 2, 37.51,   4, 2, 3, 39.78,  4, 1, 4, 45.81,
  5, 0, 1, 33.64,   5, 1, 2, 46.47,   5, 3, 3, 27.83,  5, 2, 4, 42.35,
  6, 1, 1, 86.39,   6, 2, 2, 60.50,   6, 0, 3, 57.69,  6, 3, 4, 35.46,
  7, 2, 1, 71.43,   7, 3, 2, 33.67,   7, 1, 3, 61.43,  7, 0, 4, 59.86,
  8, 3, 1, 57.76,   8, 0, 2, 78.83,   8, 2, 3, 65.04,  8, 1, 4, 85.67))
missing <- balanced[!(balanced$participant == 3 & balanced$position == 2), ]
singular <- rows(c(
  1, 0, 1, 54.62,  1, 1, 2, 68.85,  1, 3, 3, 34.43,  1, 2, 4, 64.30,
  2, 1, 1, 73.24,  2, 2, 2, 48.49,  2, 0, 3, 59.59,  2, 3, 4, 41.89,
  3, 2, 1, 62.22,  3, 3, 2, 38.80,  3, 1, 3, 80.73,  3, 0, 4, 56.42,
  4, 3, 1, 38.52,  4, 0, 2, 41.35,  4, 2, 3, 62.37,  4, 1, 4, 61.41,
  5, 0, 1, 59.85,  5, 1, 2, 77.16,  5, 3, 3, 44.15,  5, 2, 4, 55.34,
  6, 1, 1, 80.01,  6, 2, 2, 61.66,  6, 0, 3, 56.01,  6, 3, 4, 27.83,
  7, 2, 1, 62.63,  7, 3, 2, 40.28,  7, 1, 3, 62.86,  7, 0, 4, 42.68,
  8, 3, 1, 39.35,  8, 0, 2, 61.38,  8, 2, 3, 64.60,  8, 1, 4, 60.88))

g <- function(x) paste(sprintf("%.10g", x), collapse = ", ")
report <- function(name, d) {
  fit <- lmerTest::lmer(log(lap) ~ condition + position + (1 | participant), data = d, REML = TRUE)
  co <- summary(fit)$coefficients  # Estimate, Std. Error, df, t value, Pr(>|t|): Satterthwaite
  half <- qt(0.975, co[, "df"]) * co[, "Std. Error"]
  vc <- as.data.frame(VarCorr(fit))
  # The condition means at the data's mean position, on the log scale.
  mean_position <- mean(d$position)
  L <- rbind(c(1, 0, 0, 0, mean_position), c(1, 1, 0, 0, mean_position),
             c(1, 0, 1, 0, mean_position), c(1, 0, 0, 1, mean_position))
  means <- lmerTest::contest(fit, L, joint = FALSE, confint = TRUE)
  full <- lme4::lmer(log(lap) ~ condition + position + (1 | participant), data = d, REML = FALSE)
  reduced <- lme4::lmer(log(lap) ~ position + (1 | participant), data = d, REML = FALSE)
  lrt <- anova(reduced, full)
  cat("// ", name, ": ", nrow(d), " trials, singular fit: ", isSingular(fit), "\n", sep = "")
  cat("//   terms: (Intercept), condition1, condition2, condition3, position\n")
  cat("  .estimate = {", g(co[, "Estimate"]), "},\n", sep = "")
  cat("  .standard_error = {", g(co[, "Std. Error"]), "},\n", sep = "")
  cat("  .degrees_of_freedom = {", g(co[, "df"]), "},\n", sep = "")
  cat("  .p_value = {", g(co[, "Pr(>|t|)"]), "},\n", sep = "")
  cat("  .ci_low = {", g(co[, "Estimate"] - half), "},\n", sep = "")
  cat("  .ci_high = {", g(co[, "Estimate"] + half), "},\n", sep = "")
  cat("  .participant_variance = ", g(vc$vcov[vc$grp == "participant"]), ",\n", sep = "")
  cat("  .residual_variance = ", g(vc$vcov[vc$grp == "Residual"]), ",\n", sep = "")
  cat("  .reml_criterion = ", g(REMLcrit(fit)), ",\n", sep = "")
  cat("  .mean_estimate = {", g(means$Estimate), "},\n", sep = "")
  cat("  .mean_standard_error = {", g(means[["Std. Error"]]), "},\n", sep = "")
  cat("  .mean_degrees_of_freedom = {", g(means$df), "},\n", sep = "")
  cat("  .ml_deviance_full = ", g(deviance(full)), ",\n", sep = "")
  cat("  .ml_deviance_reduced = ", g(deviance(reduced)), ",\n", sep = "")
  cat("  .lrt_chi_square = ", g(lrt$Chisq[2]), ",\n", sep = "")
  cat("  .lrt_degrees_of_freedom = ", g(lrt$Df[2]), ",\n", sep = "")
  cat("  .lrt_p_value = ", g(lrt[["Pr(>Chisq)"]][2]), ",\n", sep = "")
  ft <- anova(fit)  # lmerTest: type III, Satterthwaite's F
  cat("  .f = ", g(ft["condition", "F value"]), ",\n", sep = "")
  cat("  .f_denominator_df = ", g(ft["condition", "DenDF"]), ",\n", sep = "")
  cat("  .f_p_value = ", g(ft["condition", "Pr(>F)"]), ",\n", sep = "")
}
report("balanced", balanced)
report("missing", missing)
report("singular", singular)
