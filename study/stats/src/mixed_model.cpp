#include "haptel/study/mixed_model.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <stdexcept>

#include "haptel/study/statistics.hpp"

namespace haptel::study {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

/// The data in the form the fits use: X, y and each row's participant
/// (0..participants − 1).
struct Design {
  MatrixXd x;
  VectorXd y;
  std::vector<int> group;
  int groups = 0;
};

/// Per-participant sums that make every H⁻¹ product a sum over participants:
/// with H_i = I + θ² 1 1' (n_i trials), H_i⁻¹ = I − w_i 1 1', w_i = θ²/(1 + n_i θ²).
struct GroupSums {
  std::vector<double> count;  ///< n_i
  MatrixXd x_sums;            ///< column i: X_i' 1
  VectorXd y_sums;            ///< 1' y_i
  MatrixXd xtx;
  VectorXd xty;
};

GroupSums Sums(const Design& d) {
  GroupSums s;
  s.count.assign(static_cast<size_t>(d.groups), 0.0);
  s.x_sums = MatrixXd::Zero(d.x.cols(), d.groups);
  s.y_sums = VectorXd::Zero(d.groups);
  for (Eigen::Index r = 0; r < d.x.rows(); ++r) {
    const int g = d.group[static_cast<size_t>(r)];
    s.count[static_cast<size_t>(g)] += 1.0;
    s.x_sums.col(g) += d.x.row(r).transpose();
    s.y_sums(g) += d.y(r);
  }
  s.xtx = d.x.transpose() * d.x;
  s.xty = d.x.transpose() * d.y;
  return s;
}

/// The generalized least-squares solution for one θ and what the criteria need.
struct Profile {
  double theta = 0.0;
  VectorXd beta;
  MatrixXd xt_hinv_x;  ///< X'H⁻¹X
  double q = 0.0;      ///< the penalized residual sum of squares (y − Xβ)'H⁻¹(y − Xβ)
  double log_det_h = 0.0;
  double log_det_xt_hinv_x = 0.0;
};

Profile Solve(const Design& d, const GroupSums& s, double theta) {
  Profile p;
  p.theta = theta;
  const double t2 = theta * theta;
  p.xt_hinv_x = s.xtx;
  VectorXd rhs = s.xty;
  std::vector<double> w(static_cast<size_t>(d.groups));
  for (int g = 0; g < d.groups; ++g) {
    const double n = s.count[static_cast<size_t>(g)];
    w[static_cast<size_t>(g)] = t2 / (1.0 + n * t2);
    p.xt_hinv_x -= w[static_cast<size_t>(g)] * s.x_sums.col(g) * s.x_sums.col(g).transpose();
    rhs -= w[static_cast<size_t>(g)] * s.x_sums.col(g) * s.y_sums(g);
    p.log_det_h += std::log1p(n * t2);
  }
  const Eigen::LLT<MatrixXd> llt(p.xt_hinv_x);
  p.beta = llt.solve(rhs);
  for (Eigen::Index i = 0; i < p.xt_hinv_x.rows(); ++i)
    p.log_det_xt_hinv_x += 2.0 * std::log(llt.matrixL()(i, i));
  // q from the residuals, not as y'H⁻¹y − r'β: that difference would cancel.
  const VectorXd e = d.y - d.x * p.beta;
  VectorXd e_sums = VectorXd::Zero(d.groups);
  for (Eigen::Index r = 0; r < e.size(); ++r) e_sums(d.group[static_cast<size_t>(r)]) += e(r);
  p.q = e.squaredNorm();
  for (int g = 0; g < d.groups; ++g) p.q -= w[static_cast<size_t>(g)] * e_sums(g) * e_sums(g);
  return p;
}

/// −2 log of the restricted (REML) or full (ML) likelihood, profiled over β and σ².
double Criterion(const Profile& p, double n, double fixed, bool reml) {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  if (reml) {
    const double dof = n - fixed;
    return p.log_det_h + p.log_det_xt_hinv_x + dof * (1.0 + std::log(kTwoPi * p.q / dof));
  }
  return p.log_det_h + n * (1.0 + std::log(kTwoPi * p.q / n));
}

/// Brent's minimisation of f on [a, b] without derivatives (Brent 1973,
/// "localmin": golden section with parabolic steps), to an absolute
/// tolerance of about `tolerance` in x.
double BrentMinimum(const std::function<double(double)>& f, double a, double b, double tolerance) {
  constexpr double kGolden = 0.3819660112501051;  // (3 − √5)/2
  double x = a + kGolden * (b - a);
  double w = x, v = x;
  double fx = f(x), fw = fx, fv = fx;
  double d = 0.0, e = 0.0;
  for (int iteration = 0; iteration < 500; ++iteration) {
    const double middle = 0.5 * (a + b);
    const double tol1 = 1e-10 * std::abs(x) + tolerance / 3.0;
    const double tol2 = 2.0 * tol1;
    if (std::abs(x - middle) <= tol2 - 0.5 * (b - a)) break;
    bool golden = true;
    if (std::abs(e) > tol1) {
      // A parabola through x, w, v.
      double r = (x - w) * (fx - fv);
      double q = (x - v) * (fx - fw);
      double p = (x - v) * q - (x - w) * r;
      q = 2.0 * (q - r);
      if (q > 0.0) p = -p;
      q = std::abs(q);
      const double previous_e = e;
      e = d;
      if (std::abs(p) < std::abs(0.5 * q * previous_e) && p > q * (a - x) && p < q * (b - x)) {
        d = p / q;
        const double u = x + d;
        if (u - a < tol2 || b - u < tol2) d = x < middle ? tol1 : -tol1;
        golden = false;
      }
    }
    if (golden) {
      e = (x < middle ? b : a) - x;
      d = kGolden * e;
    }
    const double u = x + (std::abs(d) >= tol1 ? d : (d > 0.0 ? tol1 : -tol1));
    const double fu = f(u);
    if (fu <= fx) {
      (u < x ? b : a) = x;
      v = w, fv = fw;
      w = x, fw = fx;
      x = u, fx = fu;
    } else {
      (u < x ? a : b) = u;
      if (fu <= fw || w == x) {
        v = w, fv = fw;
        w = u, fw = fu;
      } else if (fu <= fv || v == x || v == w) {
        v = u, fv = fu;
      }
    }
  }
  return x;
}

/// The θ = σ_b/σ minimising the criterion: a log-spaced scan over
/// [1e-4, 1e4] and θ = 0 brackets it, Brent's method refines it; θ = 0 when
/// the boundary is as good to within rounding. Not `separable` (no
/// variation within participants to tell σ from σ_b): θ = 0, unsearched.
Profile Fit(const Design& d, bool reml, bool separable) {
  const GroupSums s = Sums(d);
  if (!separable) return Solve(d, s, 0.0);
  const double n = static_cast<double>(d.y.size());
  const double fixed = static_cast<double>(d.x.cols());
  const auto criterion = [&](double theta) {
    return Criterion(Solve(d, s, theta), n, fixed, reml);
  };
  std::vector<double> grid{0.0};
  for (int k = -32; k <= 32; ++k) grid.push_back(std::pow(10.0, k / 8.0));
  size_t best = 0;
  double best_value = criterion(0.0);
  for (size_t i = 1; i < grid.size(); ++i) {
    const double value = criterion(grid[i]);
    if (value < best_value) best = i, best_value = value;
  }
  const double low = best == 0 ? 0.0 : grid[best - 1];
  const double high = grid[std::min(best + 1, grid.size() - 1)];
  double theta = BrentMinimum(criterion, low, high, 1e-12);
  if (criterion(theta) > best_value) theta = grid[best];
  // The boundary when the minimum found beside it is not better by more than
  // rounding: a participant variance of 1e-20 σ² is none.
  if (criterion(0.0) <= criterion(theta) + 1e-9) theta = 0.0;
  return Solve(d, s, theta);
}

/// The REML fit's matrices for the variance components' inference.
struct Inference {
  MatrixXd covariance;   ///< C = Var(β̂) = (X'V⁻¹X)⁻¹
  MatrixXd v_inverse_x;  ///< V⁻¹X
  MatrixXd z;            ///< the participants' indicator columns
  /// The inverse of the REML log-likelihood's observed information in
  /// (σ_b², σ²), or in σ² alone (1 × 1) at the boundary.
  MatrixXd component_covariance;
  bool boundary = false;
  double fallback_df = 0.0;  ///< n − p, when Satterthwaite's df is not finite
};

Inference Infer(const Design& d, double participant_variance, double residual_variance,
                bool boundary) {
  const Eigen::Index n = d.y.size();
  Inference in;
  in.boundary = boundary;
  in.fallback_df = static_cast<double>(n - d.x.cols());
  in.z = MatrixXd::Zero(n, d.groups);
  for (Eigen::Index r = 0; r < n; ++r) in.z(r, d.group[static_cast<size_t>(r)]) = 1.0;
  const MatrixXd v =
      residual_variance * MatrixXd::Identity(n, n) + participant_variance * in.z * in.z.transpose();
  const Eigen::LDLT<MatrixXd> v_ldlt(v);
  const MatrixXd v_inverse = v_ldlt.solve(MatrixXd::Identity(n, n));
  in.v_inverse_x = v_inverse * d.x;
  in.covariance = (d.x.transpose() * in.v_inverse_x).inverse();
  const MatrixXd p = v_inverse - in.v_inverse_x * in.covariance * in.v_inverse_x.transpose();
  const VectorXd a = p * d.y;
  // −∂²l/∂φi∂φj = −½ tr(P V_i P V_j) + y'P V_i P V_j P y for V = Σ φ_i V_i,
  // V_σb² = Z Z', V_σ² = I.
  const double info_residual = -0.5 * p.squaredNorm() + a.dot(p * a);
  if (boundary) {
    in.component_covariance = MatrixXd::Constant(1, 1, 1.0 / info_residual);
    return in;
  }
  const MatrixXd pz = p * in.z;
  const MatrixXd ztpz = in.z.transpose() * pz;
  const VectorXd zta = in.z.transpose() * a;
  MatrixXd info(2, 2);
  info(0, 0) = -0.5 * ztpz.squaredNorm() + zta.dot(ztpz * zta);
  info(0, 1) = info(1, 0) = -0.5 * pz.squaredNorm() + zta.dot(in.z.transpose() * (p * a));
  info(1, 1) = info_residual;
  in.component_covariance = info.inverse();
  return in;
}

MixedModelContrast Contrast(const VectorXd& l, const VectorXd& beta, const Inference& in,
                            std::vector<std::string>& notes) {
  MixedModelContrast c;
  c.estimate = l.dot(beta);
  const VectorXd cl = in.covariance * l;
  const double variance = l.dot(cl);
  c.standard_error = std::sqrt(std::max(variance, 0.0));
  // g_i = ∂(l'Cl)/∂φ_i = u' V_i u with u = V⁻¹XCl.
  const VectorXd u = in.v_inverse_x * cl;
  VectorXd g(in.boundary ? 1 : 2);
  if (in.boundary) {
    g(0) = u.squaredNorm();
  } else {
    g(0) = (in.z.transpose() * u).squaredNorm();
    g(1) = u.squaredNorm();
  }
  const double spread = g.dot(in.component_covariance * g);
  c.degrees_of_freedom = 2.0 * variance * variance / spread;
  if (!std::isfinite(c.degrees_of_freedom) || !(c.degrees_of_freedom > 0.0)) {
    notes.push_back(
        "Satterthwaite's degrees of freedom were not finite for one contrast; it uses n - p = " +
        Number(in.fallback_df));
    c.degrees_of_freedom = in.fallback_df;
  }
  if (c.standard_error > 0.0) {
    c.t = c.estimate / c.standard_error;
    c.p_value = StudentTTwoSidedP(c.t, c.degrees_of_freedom);
  }
  const double half = StudentTQuantile(0.975, c.degrees_of_freedom) * c.standard_error;
  c.ci_low = c.estimate - half;
  c.ci_high = c.estimate + half;
  return c;
}

int Rank(const MatrixXd& x) {
  Eigen::ColPivHouseholderQR<MatrixXd> qr(x);
  qr.setThreshold(1e-10);
  return static_cast<int>(qr.rank());
}

}  // namespace

MixedModelResult FitMixedModel(const std::vector<MixedModelObservation>& observations,
                               int conditions, int reference) {
  const std::string what = "mixed model";
  if (conditions < 2) {
    throw std::invalid_argument(what + ": expected at least 2 conditions, got " +
                                std::to_string(conditions));
  }
  if (reference < 0 || reference >= conditions) {
    throw std::invalid_argument(what + ": expected a reference condition in 0.." +
                                std::to_string(conditions - 1) + ", got " +
                                std::to_string(reference));
  }
  std::map<int, int> group_of;
  std::vector<int> per_condition(static_cast<size_t>(conditions), 0);
  for (size_t i = 0; i < observations.size(); ++i) {
    const MixedModelObservation& o = observations[i];
    if (o.condition < 0 || o.condition >= conditions) {
      throw std::invalid_argument(what + ": observation " + std::to_string(i) + " has condition " +
                                  std::to_string(o.condition) + ", expected 0.." +
                                  std::to_string(conditions - 1));
    }
    if (!std::isfinite(o.response) || !std::isfinite(o.position)) {
      throw std::invalid_argument(what + ": observation " + std::to_string(i) +
                                  " expected a finite response and position, got " +
                                  Number(o.response) + " and " + Number(o.position));
    }
    group_of.emplace(o.participant, static_cast<int>(group_of.size()));
    per_condition[static_cast<size_t>(o.condition)] += 1;
  }
  if (group_of.size() < 2) {
    throw std::invalid_argument(what + ": expected at least 2 participants, got " +
                                std::to_string(group_of.size()) +
                                " (the participants' variance needs more than one)");
  }
  std::vector<int> with_data;
  for (int c = 0; c < conditions; ++c) {
    if (per_condition[static_cast<size_t>(c)] > 0) with_data.push_back(c);
  }
  if (with_data.size() < 2) {
    throw std::invalid_argument(what + ": expected trials in at least 2 conditions, got " +
                                std::to_string(with_data.size()));
  }
  if (observations.size() <= group_of.size()) {
    throw std::invalid_argument(
        what + ": expected some participant with more than one trial (" +
        std::to_string(observations.size()) + " trials, " + std::to_string(group_of.size()) +
        " participants): the participants' variance cannot be told from the residual");
  }

  MixedModelResult result;
  result.observations = static_cast<int>(observations.size());
  result.participants = static_cast<int>(group_of.size());
  result.conditions.resize(static_cast<size_t>(conditions));
  result.reference_condition = reference;
  if (per_condition[static_cast<size_t>(reference)] == 0) {
    result.reference_condition = with_data.front();
    result.notes.push_back("the reference condition " + std::to_string(reference) +
                           " has no trials; the others are compared with condition " +
                           std::to_string(with_data.front()) + ", the first with trials");
  }
  // Columns: intercept, one per condition with data other than the
  // reference, then the position.
  std::vector<int> column_of(static_cast<size_t>(conditions), -1);
  int columns = 1;
  for (const int c : with_data) {
    if (c != result.reference_condition) column_of[static_cast<size_t>(c)] = columns++;
  }
  const int condition_columns = columns - 1;
  int position_column = columns++;

  Design full;
  const Eigen::Index n = static_cast<Eigen::Index>(observations.size());
  full.groups = static_cast<int>(group_of.size());
  full.x = MatrixXd::Zero(n, columns);
  full.y.resize(n);
  double position_sum = 0.0;
  for (Eigen::Index r = 0; r < n; ++r) {
    const MixedModelObservation& o = observations[static_cast<size_t>(r)];
    full.x(r, 0) = 1.0;
    if (column_of[static_cast<size_t>(o.condition)] >= 0)
      full.x(r, column_of[static_cast<size_t>(o.condition)]) = 1.0;
    full.x(r, position_column) = o.position;
    full.y(r) = o.response;
    full.group.push_back(group_of.at(o.participant));
    position_sum += o.position;
  }
  result.mean_position = position_sum / static_cast<double>(n);
  if (Rank(full.x) < columns) {
    // The position is what is left out: the conditions are the question.
    full.x.conservativeResize(Eigen::NoChange, columns - 1);
    --columns;
    position_column = -1;
    result.notes.push_back(
        "the position is left out: it is a function of the condition (every participant ran the "
        "conditions in "
        "the same order), so learning cannot be told apart from the conditions");
    if (Rank(full.x) < columns) {
      throw std::invalid_argument(what +
                                  ": the conditions' columns are not independent (internal error)");
    }
  }
  if (n <= columns) {
    throw std::invalid_argument(what + ": expected more trials than the " +
                                std::to_string(columns) + " fixed effects, got " +
                                std::to_string(n));
  }
  {
    const Eigen::LLT<MatrixXd> llt(full.x.transpose() * full.x);
    const VectorXd residual = full.y - full.x * llt.solve(full.x.transpose() * full.y);
    if (residual.squaredNorm() <= 1e-20 * std::max(1.0, full.y.squaredNorm())) {
      throw std::invalid_argument(
          what +
          ": the fixed effects fit every trial exactly (e.g. every lap at the cap); "
          "there is no variation left to estimate a variance from");
    }
  }

  // The residual variance is told from the participants' by the variation
  // within participants that the fixed effects leave: n − rank([X Z]) df of
  // it. With none (e.g. 2 participants × 2 trials with condition and
  // position fitted) every θ = σ_b/σ explains the data equally (REML's
  // criterion is flat in θ, and ML's grows without bound as σ² → 0), so a
  // fit would put the residual variance at whatever rounding picks, often
  // ~0, and find any difference "significant". There the participants'
  // variance is set to 0: ordinary least squares, whose residual holds the
  // participants' differences too, so its tests are conservative, not
  // liberal.
  MatrixXd with_participants(n, columns + full.groups);
  with_participants << full.x, MatrixXd::Zero(n, full.groups);
  for (Eigen::Index r = 0; r < n; ++r)
    with_participants(r, columns + full.group[static_cast<size_t>(r)]) = 1.0;
  const bool separable = Rank(with_participants) < n;
  if (!separable) {
    result.notes.push_back(
        "no variation within participants is left once the fixed effects are fitted (" +
        std::to_string(n) + " trials, " + std::to_string(full.groups) + " participants, " +
        std::to_string(columns) +
        " fixed effects), so the participants' variance cannot be told from the residual's: it is "
        "set to 0 "
        "(ordinary least squares; the tests are conservative)");
  }

  const double fixed = static_cast<double>(columns);
  const Profile reml = Fit(full, true, separable);
  result.reml_criterion = Criterion(reml, static_cast<double>(n), fixed, true);
  result.residual_variance = reml.q / (static_cast<double>(n) - fixed);
  result.participant_variance = reml.theta * reml.theta * result.residual_variance;
  result.boundary = reml.theta == 0.0;
  if (result.boundary) {
    result.notes.push_back(
        "REML puts no variance between participants (a boundary fit, lme4's 'singular'): the fit "
        "is ordinary "
        "least squares and the t tests have n - p degrees of freedom");
  }
  const Inference inference =
      Infer(full, result.participant_variance, result.residual_variance, result.boundary);

  for (int c = 0; c < conditions; ++c) {
    MixedModelCondition& condition = result.conditions[static_cast<size_t>(c)];
    condition.reference = c == result.reference_condition;
    condition.estimable = per_condition[static_cast<size_t>(c)] > 0;
    if (!condition.estimable) continue;
    VectorXd mean = VectorXd::Zero(columns);
    mean(0) = 1.0;
    if (position_column >= 0) mean(position_column) = result.mean_position;
    if (!condition.reference) {
      const int column = column_of[static_cast<size_t>(c)];
      VectorXd effect = VectorXd::Zero(columns);
      effect(column) = 1.0;
      condition.effect = Contrast(effect, reml.beta, inference, result.notes);
      mean(column) = 1.0;
    }
    condition.mean = Contrast(mean, reml.beta, inference, result.notes);
  }
  if (position_column >= 0) {
    VectorXd slope = VectorXd::Zero(columns);
    slope(position_column) = 1.0;
    result.position = Contrast(slope, reml.beta, inference, result.notes);
  }

  // The condition as a whole, first by Satterthwaite's F test of its
  // contrasts (lmerTest's contestMD): rotated to the eigenvectors of L C L'
  // the contrasts are independent, each a t test with its own df.
  MixedModelConditionTest& test = result.condition_test;
  test.degrees_of_freedom = condition_columns;
  {
    MatrixXd l = MatrixXd::Zero(condition_columns, columns);
    for (int row = 0; row < condition_columns; ++row)
      l(row, row + 1) = 1.0;  // the columns after the intercept
    const Eigen::SelfAdjointEigenSolver<MatrixXd> eigen(l * inference.covariance * l.transpose());
    double t_squares = 0.0;
    std::vector<double> dfs;
    for (int i = 0; i < condition_columns; ++i) {
      const MixedModelContrast rotated =
          Contrast(l.transpose() * eigen.eigenvectors().col(i), reml.beta, inference, result.notes);
      t_squares += rotated.t * rotated.t;
      dfs.push_back(rotated.degrees_of_freedom);
    }
    test.f = t_squares / condition_columns;
    test.denominator_df = dfs.front();
    const bool all_equal = std::all_of(
        dfs.begin(), dfs.end(), [&](double df) { return std::abs(df - dfs.front()) < 1e-8; });
    if (!all_equal) {
      // lmerTest's get_Fstat_ddf: 2 when any ν_i ≤ 2 (the F's mean is not finite).
      double e = 0.0;
      bool small = false;
      for (const double df : dfs) {
        if (df <= 2.0) small = true;
        e += df / (df - 2.0);
      }
      test.denominator_df = small ? 2.0 : 2.0 * e / (e - condition_columns);
    }
    const double q = condition_columns;
    const double d = test.denominator_df;
    // P(F > f) = I_{d/(d + q f)}(d/2, q/2).
    test.p_value =
        test.f > 0.0 ? RegularizedIncompleteBeta(d / 2.0, q / 2.0, d / (d + q * test.f)) : 1.0;
  }

  // Then for comparison the likelihood ratio: ML refits with and without its columns.
  Design reduced = full;
  reduced.x = MatrixXd(n, columns - condition_columns);
  reduced.x.col(0) = full.x.col(0);
  if (position_column >= 0) reduced.x.col(1) = full.x.col(position_column);
  const Profile ml_full = Fit(full, false, separable);
  const Profile ml_reduced = Fit(reduced, false, separable);
  test.ml_deviance_full = Criterion(ml_full, static_cast<double>(n), fixed, false);
  test.ml_deviance_reduced =
      Criterion(ml_reduced, static_cast<double>(n), static_cast<double>(reduced.x.cols()), false);
  test.chi_square = std::max(0.0, test.ml_deviance_reduced - test.ml_deviance_full);
  test.likelihood_ratio_p_value = ChiSquareSurvival(test.chi_square, test.degrees_of_freedom);

  std::sort(result.notes.begin(), result.notes.end());
  result.notes.erase(std::unique(result.notes.begin(), result.notes.end()), result.notes.end());
  result.method =
      "REML fit with a random intercept per participant (lme4's criterion); per-condition t tests "
      "with Satterthwaite's degrees of freedom (as lmerTest); the condition as a whole by "
      "Satterthwaite's F test (as lmerTest's anova), a likelihood-ratio test of ML refits beside "
      "it";
  return result;
}

}  // namespace haptel::study
