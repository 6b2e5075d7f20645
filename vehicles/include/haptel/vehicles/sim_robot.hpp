#pragma once
/// @file The simulated Lego-style tank: differential drive on a track.
///
/// Two motors take quantised speed levels; each tread follows its level with
/// a first-order lag and its own gain (uneven turning). The body is a circle
/// that cannot enter walls, gate posts or obstacles: a move into one is
/// projected back out (the robot slides along), and a contact ahead of the
/// robot closes the left, the right or both front bumper switches. Its range
/// sensors (config range_sensors) scan the walls and posts after each step.
///
/// It runs a *reality* (config/reality.hpp), not its vehicle file's model:
/// the treads' true gains and lag, skid (an effective track width, a
/// sideways slip growing with speed × turn rate), the battery's fade,
/// floor patches where the body moves by only part of the treads' speed,
/// command and state jitter. Its state says what the robot itself knows:
/// with the reality's `odometry`, the pose it integrates from its tread
/// encoders along its gyro's heading (both noisy), which drifts from the
/// truth; bumpers; ranges scanned from where it truly is, against the walls
/// and posts where they truly stand (the reality's map error), with its
/// false and missing echoes. Truth() says
/// where it truly is, for the truth record only. Without a reality file
/// (NominalReality) it is the file's model exactly, and reports the truth.
#include <array>
#include <random>

#include "haptel/config/reality.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/models/tread_drive.hpp"
#include "haptel/vehicles/adapter.hpp"
#include "haptel/vehicles/range_sensors.hpp"

namespace haptel::vehicles {

class SimRobot final : public VehicleAdapter {
 public:
  /// Keeps a reference to `track`; starts at the track's start pose. Validates
  /// `config` first (VehicleConfig::ValidateOrThrow: ConfigFieldError); runs
  /// the config's reality (VehicleReality: its `reality` file drawn, or none).
  SimRobot(const Track& track, const VehicleConfig& config);
  /// The same in a reality already drawn.
  SimRobot(const Track& track, const VehicleConfig& config, const DrawnReality& reality);

  void SetMotors(const models::MotorLevels& levels) override;
  /// Drives the treads at these speeds (m/s) instead of the levels (the
  /// emulated motor controllers of the simulated CAN robot); each still
  /// follows with the motor lag and its gain. SetMotors switches back.
  void SetTreadTargets(double left, double right);
  void Update(double dt) override;
  AdapterState State() const override { return state_; }
  const DrawnReality* reality() const override { return &reality_; }
  bool Truth(TruthRow* row) const override;

  /// Test hook: puts the robot at rest at a pose (its odometry there too).
  void Place(double x, double y, double heading);
  /// Tread speeds, m/s.
  double left_speed() const { return v_left_; }
  double right_speed() const { return v_right_; }
  /// The traction of the floor at (x, y): 1, or the patch's there.
  double TractionAt(double x, double y) const;

 private:
  /// What the robot measured at one tick (for the state's jitter).
  struct Measured {
    double t_s = 0.0;
    double x = 0.0, y = 0.0, heading = 0.0, speed = 0.0, yaw_rate = 0.0;
  };
  /// s: the longest step of the body (Update steps a longer time in pieces).
  static constexpr double kMaxStep_s = 0.05;
  /// Moves the robot, its measurements and its state on by `dt` (at most kMaxStep_s).
  void Step(double dt);
  /// Moves the true body one step; returns its yaw rate.
  double StepBody(double target_left, double target_right, double dt);
  /// Integrates the encoders and the gyro over a step of the true motion.
  void StepOdometry(double yaw_rate, double dt);
  /// Pushes the body out of every obstacle; sets the bumper switches.
  void ResolveContacts();
  void Contact(const Vec2& point);
  double Gaussian() { return normal_(noise_); }
  /// The scan from the true pose against the true walls and posts.
  RangeScan Scan();

  const Track& track_;
  TreadDriveConfig drive_;       ///< the file's: the levels' speeds
  TreadDriveConfig true_drive_;  ///< the reality's gains, lag and effective track width
  DrawnReality reality_;
  BodyConfig body_;
  RangeSensorConfig range_sensors_;
  std::mt19937_64 range_noise_;
  RangeFaults range_faults_;
  std::mt19937_64 echoes_;  ///< the range faults' draws
  std::mt19937_64 noise_;   ///< encoders, gyro, jitter
  std::normal_distribution<double> normal_{0.0, 1.0};
  models::MotorLevels levels_;   ///< the motors run at these
  models::MotorLevels pending_;  ///< commanded, in effect at pending_due_s_
  double pending_due_s_ = -1.0;  ///< < 0: nothing pending
  bool use_treads_ = false;
  double tread_left_ = 0.0;
  double tread_right_ = 0.0;
  double v_left_ = 0.0;
  double v_right_ = 0.0;
  double time_s_ = 0.0;
  /// The truth: pose (x, y, heading), speed and yaw rate.
  models::TreadState truth_;
  double true_speed_ = 0.0;
  double true_yaw_rate_ = 0.0;
  /// The robot's own estimate (with the reality's odometry).
  models::TreadState odometry_;
  double measured_speed_ = 0.0;
  double measured_yaw_rate_ = 0.0;
  std::array<Measured, 16> measured_{};  ///< the last ticks, newest at measured_next_ - 1
  size_t measured_next_ = 0;
  size_t measured_count_ = 0;
  AdapterState state_;
};

}  // namespace haptel::vehicles
