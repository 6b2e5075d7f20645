#pragma once
/// @file The seam between a vehicle node and what it drives: a simulator or
/// a hardware adapter (SocketCAN robot, servo-controller blimp).
#include <cstdint>
#include <string>

#include "haptel/config/reality.hpp"
#include "haptel/config/truth_format.hpp"
#include "haptel/core/range_scan.hpp"
#include "haptel/models/tread_drive.hpp"

namespace haptel::vehicles {

/// What an adapter knows about its vehicle.
struct AdapterState {
  double speed = 0.0;     ///< m/s, forward positive
  double yaw_rate = 0.0;  ///< rad/s, counter-clockwise positive
  bool pose_valid = false;
  double x = 0.0;  ///< m
  double y = 0.0;
  double heading = 0.0;  ///< rad
  bool bumper_left = false;
  bool bumper_right = false;
  models::MotorLevels applied;  ///< levels the motors run at now
  /// The vehicle stopped itself (a motor controller's error, a silent node,
  /// bus-off) and will not move until its faults are cleared.
  bool fault = false;
  std::string fault_message;  ///< one line: what, where (empty: no fault)
  /// What the range sensors see now (count 0: the vehicle has none).
  RangeScan ranges;
  /// How long before now the pose, speed and yaw rate were measured (a
  /// simulator's state jitter, config/reality.hpp): the state's stamp says so.
  double measured_age_s = 0.0;
};

class VehicleAdapter {
 public:
  virtual ~VehicleAdapter() = default;
  /// Sets the motor speed levels (already quantised).
  virtual void SetMotors(const models::MotorLevels& levels) = 0;
  /// Stops every motor at once (the command watchdog, shutdown); the next
  /// SetMotors drives again. Hardware may do more (idle the controllers).
  virtual void Stop() { SetMotors({}); }
  /// Advances by dt seconds: simulators step, hardware polls its bus.
  virtual void Update(double dt) = 0;
  virtual AdapterState State() const = 0;
  /// A simulator's drawn reality (its truth record's header, its clock);
  /// null: hardware, whose truth nobody knows.
  virtual const DrawnReality* reality() const { return nullptr; }
  /// Where the vehicle truly is (a simulator; false: hardware). The
  /// caller stamps operator_ns.
  virtual bool Truth(TruthRow*) const { return false; }
};

}  // namespace haptel::vehicles
