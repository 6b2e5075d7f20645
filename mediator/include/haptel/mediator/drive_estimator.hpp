#pragma once
/// @file What the operator side learns of the tank robot it drives: each
/// tread's gain (its speed per level against the vehicle file's) and the
/// effective track width, online, from the states alone (the odometry's
/// speed and yaw rate, the levels the robot says it applied, the vehicle's
/// stamps). Never from the simulator's truth: a real robot gives no more.
///
/// The model is the predictor's own (models/tread_drive.hpp): each tread
/// follows gain × its level's speed through the motor's first-order lag,
/// and
///
///     speed    = (g_l u_l + g_r u_r) / 2
///     yaw rate = (g_r u_r − g_l u_l) / B
///
/// where u is a level's nominal speed passed through the lag (the vehicle
/// file's time constant, from the applied levels between two states) and B
/// the effective track width: a skid-steer turns slower than its geometric
/// width says, because its treads slip sideways (Martínez et al., IJRR 2005,
/// "Approximating kinematics for tracked mobile robots"; Mandow et al., IROS
/// 2007, "Experimental kinematics for wheeled skid-steer mobile robots", who
/// fit it as an expansion factor of the geometric width). Both lines are
/// linear in their parameters: (g_l, g_r) from the speed, and (a_l, a_r) =
/// (g_l / B, g_r / B) from the yaw rate, each by recursive least squares
/// with exponential forgetting (Ljung, "System Identification", 2nd ed.
/// 1999, §11.2), so that slow changes (the battery's sag) are followed.
///
/// What each line shows decides what is taken from it. The speed shows the
/// mean gain m = (g_l + g_r) / 2 at once (every state moving), but the split
/// between the treads only in turns, and then faintly (on harsh's grand prix
/// it took 18 s to be known, and was split the wrong way round before: 0.73
/// / 0.90 against 0.83 / 0.79). The yaw rate shows the split strongly, even
/// driven straight (a_r − a_l: a tank that pulls to one side), and the sum
/// a_l + a_r in turns. So: m from the speed; the ratio g_r / g_l = a_r / a_l
/// from the yaw rate (the file's until known: a prior that holds the split
/// where the file says until the data say otherwise); each gain m split by
/// that ratio; and B = 2 m / (a_l + a_r). Driven straight, the yaw rate's
/// estimator updates without forgetting: it learns the difference and
/// forgets nothing of the sum it did not see (Kulhavý 1987, restricted
/// forgetting), so the sum is not wound up between turns.
///
/// Guards, so that what it has not seen does not move it:
/// - no update while a bumper is pressed (the treads stall, the robot does
///   not move), while the robot is at rest with no level applied (nothing
///   to learn), nor across a gap in the states, nor after either until the
///   lag has settled (its state is lost);
/// - a state sampled no later than the one before (out of sequence: a
///   vehicle's state jitter) is left out;
/// - each covariance's trace is bounded (no wind-up), and reset when the
///   residuals keep one sign, each over the noise, for half a second (the
///   robot changed: a battery that sagged);
/// - a floor patch of less grip is not a new robot: the gyro sees the body
///   turn less while the encoders still see the treads' speed, so it shows
///   as a burst of yaw-rate residuals of one sign and nothing in the speed.
///   The yaw rate's residuals are therefore clipped at kOutlierSds noise
///   deviations once the width is known (Huber's M-estimator: a burst pulls
///   by a bounded step each; Huber 1981, Ljung 1999 §15.2), and its
///   covariance is reset only when the speed's was too (a battery that
///   sagged changes both), or when the burst outlasts any patch's crossing
///   (`width_reset_run`: then the robot did change). Resetting on every
///   burst is the covariance wind-up's opposite failure: the estimate
///   follows the floor (Åström & Wittenmark, "Adaptive Control", 2nd ed.
///   1995, §11.2 on forgetting and resetting: reset only on evidence that
///   the parameters changed);
/// - estimates are clamped to bounds (gains 0.3–2, width 0.8–3× the
///   file's), and used once each has first been known to 5 % (its standard
///   deviation, from the covariance and the residuals' noise:
///   gains_known(), width_known()), from then on. (Using an estimate once
///   it is two deviations from the file's value instead latched a gain at
///   0.51 against a truth of 0.83 on harsh's grand prix: the deviations the
///   covariance gives are too small there, the residuals being neither
///   white nor Gaussian: the motor lag's misfit, the jitter.) The mean gain
///   is known when its deviation is under 5 %, the ratio under 0.02, the
///   width when both its parameters are under 5 %.
///
/// The motor's time constant is not estimated: the vehicle file's is used.
/// Its misfit shows in the gains during speed changes only.
///
/// Allocates nothing; a few dozen flops a state.
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/recursive_least_squares.hpp"

namespace haptel::mediator {

/// One state as the estimator needs it.
struct DriveObservation {
  double stamp_s = 0.0;   ///< when it was sampled, the vehicle's clock (s)
  double speed = 0.0;     ///< m/s
  double yaw_rate = 0.0;  ///< rad/s
  int applied_left = 0;   ///< levels in effect
  int applied_right = 0;
  bool touching = false;  ///< a bumper pressed
};

class DriveEstimator {
 public:
  struct Options {
    /// Per state (50 Hz): a memory of 1/(1 − λ) = 500 states, 10 s.
    double forgetting = 0.998;
    /// Initial covariance (per unit noise variance): a prior worth nothing.
    double initial_covariance = 1e10;
    /// The bound on each covariance's trace once known, and what a reset
    /// starts again from (per unit noise variance, gain²; the width's
    /// parameters scaled by the file's width²).
    double reset_covariance = 100.0;
    /// A parameter is known once its standard deviation is under this
    /// share of its value: well inside what the file's numbers may be off
    /// by (a motor's gain by 5-10 %, a skid-steer's width by 20-60 %).
    double known_share = 0.05;
    /// The treads' gain ratio g_r / g_l is known once its standard
    /// deviation is under this (a 2 % ratio: each gain within 1 %).
    double known_ratio_sd = 0.02;
    /// The measurements' noise is never taken as less than this (m/s; rad/s).
    double speed_noise_floor = 0.002;
    double yaw_noise_floor = 0.01;
    /// A turn (it shows the width): the nominal tread speeds differ by this
    /// share of the top speed. The yaw rate's estimator forgets only in
    /// turns; width_updates() counts them.
    double min_turn = 0.15;
    /// A moving robot: some tread's nominal speed over this share of the top speed.
    double min_motion = 0.05;
    /// A gap (vehicle clock, s) over which the lag's state is taken as lost.
    double max_gap_s = 0.5;
    /// Residuals of one sign, each over the noise, for this many updates in
    /// a row reset the covariance (half a second at 50 Hz).
    int reset_run = 25;
    /// The yaw rate's residuals pull no further than this many noise
    /// deviations once the width is known: 2.5 leaves Gaussian noise
    /// nearly untouched (1.2 % of residuals clipped, 99 % efficiency).
    double outlier_sds = 2.5;
    /// Yaw-rate outliers of one sign for this many width updates in a row
    /// reset the width's covariance when the speed's estimator saw no
    /// change: 3 s of turning at 50 Hz, longer than a robot of the shipped
    /// make crosses the widest patch a reality draws (harsh: up to 0.35 m
    /// across at 0.15 m/s, its speed in a tight turn: 2.3 s).
    int width_reset_run = 150;
    /// A reset of the speed's estimator this recently (vehicle clock, s)
    /// lets the width's reset after reset_run, as before: the robot changed.
    double changed_window_s = 3.0;
  };

  explicit DriveEstimator(const TreadDriveConfig& nominal) : DriveEstimator(nominal, Options{}) {}
  DriveEstimator(const TreadDriveConfig& nominal, const Options& options);

  void Observe(const DriveObservation& state);

  /// Estimates (the vehicle file's values until known; clamped to their bounds).
  double left_gain() const;
  double right_gain() const;
  double track_width() const;  ///< m
  /// The right tread's gain over the left's (the file's until known).
  double gain_ratio() const;
  bool gains_known() const { return gains_known_; }
  bool ratio_known() const { return ratio_known_; }
  bool width_known() const { return width_known_; }
  /// The vehicle file's drive with what is known in place of its numbers.
  TreadDriveConfig Drive() const;

  /// When (vehicle clock, s) each first became known (negative: not yet).
  double gains_known_at_s() const { return gains_known_at_s_; }
  double width_known_at_s() const { return width_known_at_s_; }
  double ratio_known_at_s() const { return ratio_known_at_s_; }
  int gain_updates() const { return gain_updates_; }
  int width_updates() const { return width_updates_; }
  int resets() const { return resets_; }

 private:
  /// After an update of `rls` with `residual`: bounds its covariance once
  /// known, resets it after outliers of one sign in a row (`run`: their
  /// count, signed)
  /// (`reset_after` of them); returns whether it reset.
  bool Guard(RecursiveLeastSquares2& rls, double reset_covariance, bool known, double residual,
             int& run, int reset_after);
  bool Known(const RecursiveLeastSquares2& rls) const;
  /// (g_l + g_r) / 2 from the speed, and its standard deviation.
  double MeanGain() const;
  double MeanGainSd() const;
  /// a_r / a_l = g_r / g_l from the yaw rate, and its standard deviation.
  double Ratio() const;
  double RatioSd() const;

  TreadDriveConfig nominal_;
  Options options_;
  // The lagged nominal tread speeds (m/s) and the stamp they are at.
  double u_left_ = 0.0, u_right_ = 0.0;
  double last_stamp_s_ = 0.0;
  bool seeded_ = false;
  double settled_s_ = 0.0;  ///< no update before (vehicle clock): the lag seeded
  /// (g_l, g_r) from the speed; (g_l / B, g_r / B) from the yaw rate.
  RecursiveLeastSquares2 gains_, per_width_;
  bool gains_known_ = false, width_known_ = false, ratio_known_ = false;
  double gains_known_at_s_ = -1.0, width_known_at_s_ = -1.0, ratio_known_at_s_ = -1.0;
  int gain_updates_ = 0, width_updates_ = 0, resets_ = 0;
  int gain_outliers_ = 0, width_outliers_ = 0;
  double gains_reset_at_s_ = -1e300;  ///< the speed's estimator's last reset (vehicle clock)
};

}  // namespace haptel::mediator
