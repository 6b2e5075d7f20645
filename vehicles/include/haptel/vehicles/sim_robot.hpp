#pragma once
/// @file The simulated Lego-style tank: differential drive on a track.
///
/// Two motors take quantised speed levels; each tread follows its level with
/// a first-order lag and its own gain (uneven turning). The body is a circle
/// that cannot enter walls, gate posts or obstacles: a move into one is
/// projected back out (the robot slides along), and a contact ahead of the
/// robot closes the left, the right or both front bumper switches. Its range
/// sensors (config range_sensors) scan the walls and posts after each step.
#include <random>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/models/tread_drive.hpp"
#include "haptel/vehicles/adapter.hpp"

namespace haptel::vehicles {

class SimRobot final : public VehicleAdapter {
 public:
  /// Keeps a reference to `track`; starts at the track's start pose. Validates
  /// `config` first (VehicleConfig::ValidateOrThrow: ConfigFieldError).
  SimRobot(const Track& track, const VehicleConfig& config);

  void SetMotors(const models::MotorLevels& levels) override;
  /// Drives the treads at these speeds (m/s) instead of the levels (the
  /// emulated motor controllers of the simulated CAN robot); each still
  /// follows with the motor lag and its gain. SetMotors switches back.
  void SetTreadTargets(double left, double right);
  void Update(double dt) override;
  AdapterState State() const override { return state_; }

  /// Test hook: puts the robot at rest at a pose.
  void Place(double x, double y, double heading);
  /// Tread speeds, m/s.
  double left_speed() const { return v_left_; }
  double right_speed() const { return v_right_; }

 private:
  /// Pushes the body out of every obstacle; sets the bumper switches.
  void ResolveContacts();
  void Contact(const Vec2& point);

  const Track& track_;
  TreadDriveConfig drive_;
  BodyConfig body_;
  RangeSensorConfig range_sensors_;
  std::mt19937_64 range_noise_;
  models::MotorLevels levels_;
  bool use_treads_ = false;
  double tread_left_ = 0.0;
  double tread_right_ = 0.0;
  double v_left_ = 0.0;
  double v_right_ = 0.0;
  AdapterState state_;
};

}  // namespace haptel::vehicles
