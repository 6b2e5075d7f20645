#pragma once
/// @file The simulated CAN robot: the two ODrive motor controllers and the
/// bumper I/O node emulated around SimRobot on the far end of a bus, and the
/// real CanRobot adapter on the near end (kind can-robot-sim). Every
/// command the robot obeys went through the adapter's encoder, the bus and
/// the emulated nodes' decoders.
///
/// The emulated ODrive: idle until asked for closed loop (refused with
/// INVALID_STATE while an error is set), velocity control with the velocity
/// ramp, estop, clear errors; heartbeat every `can.heartbeat_period_s`,
/// encoder estimates every 10 ms. The I/O node: heartbeat, and its inputs
/// every 20 ms and on change. Faults can be injected (tests): an axis error,
/// a silent node, an error frame.
#include <array>
#include <memory>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/vehicles/can_bus.hpp"
#include "haptel/vehicles/can_robot.hpp"
#include "haptel/vehicles/sim_robot.hpp"

namespace haptel::vehicles {

/// The emulated nodes on their end of the bus, driving a SimRobot.
class SimCanNodes {
 public:
  SimCanNodes(std::unique_ptr<CanBus> bus, const VehicleConfig& config, SimRobot& robot);
  /// Reads the frames waiting, advances the ramps, the robot and the cyclic
  /// messages by dt.
  void Step(double dt);

  /// Sets error bits on an axis (0 left, 1 right): it drops to idle.
  void InjectAxisError(int wheel, uint32_t bits);
  /// A node (0 left, 1 right, 2 I/O) stops sending (true) or resumes.
  void Silence(int node, bool silent);
  /// Puts an error frame on the bus (e.g. CAN_ERR_BUSOFF).
  void SendErrorFrame(uint32_t error_class, const std::array<uint8_t, 8>& data = {});

  uint32_t axis_state(int wheel) const { return axes_[static_cast<size_t>(wheel)].state; }
  uint32_t axis_error(int wheel) const { return axes_[static_cast<size_t>(wheel)].error; }
  float input_vel(int wheel) const { return axes_[static_cast<size_t>(wheel)].input_vel; }
  float vel(int wheel) const { return axes_[static_cast<size_t>(wheel)].vel; }
  double heartbeat_period_s() const { return can_.heartbeat_period_s; }
  uint64_t frames_in() const { return frames_in_; }
  uint64_t frames_refused() const { return frames_refused_; }

 private:
  struct Axis {
    int node = 0;
    uint32_t state = 1;  ///< idle
    uint32_t error = 0;
    uint32_t control_mode = 2;
    uint32_t input_mode = 1;
    float input_vel = 0.0F;
    float vel = 0.0F;  ///< after the ramp, turn/s
    double pos = 0.0;  ///< turns
  };
  void Handle(const can_frame& f);

  std::unique_ptr<CanBus> bus_;
  CanConfig can_;
  TreadDriveConfig drive_;
  SimRobot& robot_;
  std::array<Axis, 2> axes_;
  std::array<bool, 3> silent_{};
  double t_s_ = 0.0;
  double next_heartbeat_s_ = 0.0;
  double next_encoder_s_ = 0.0;
  double next_inputs_s_ = 0.0;
  bool last_left_ = false;
  bool last_right_ = false;
  uint8_t inputs_counter_ = 0;
  uint64_t frames_in_ = 0;
  uint64_t frames_refused_ = 0;
};

/// kind can-robot-sim: CanRobot ↔ socket pair ↔ SimCanNodes ↔ SimRobot, in
/// lock step on the vehicle node's control loop. Its pose is the
/// simulation's (as a tracking system would report a real robot's); speed,
/// motors, bumpers and faults are what came over the bus.
class SimulatedCanRobot final : public VehicleAdapter {
 public:
  SimulatedCanRobot(const Track& track, const VehicleConfig& config,
                    std::unique_ptr<CandumpWriter> log = nullptr);
  void SetMotors(const models::MotorLevels& levels) override { adapter_->SetMotors(levels); }
  void Stop() override { adapter_->Stop(); }
  void Update(double dt) override;
  AdapterState State() const override;
  const DrawnReality* reality() const override { return robot_.reality(); }
  bool Truth(TruthRow* row) const override { return robot_.Truth(row); }

  CanRobot& adapter() { return *adapter_; }
  SimCanNodes& nodes() { return *nodes_; }
  SimRobot& robot() { return robot_; }

 private:
  SimRobot robot_;
  std::unique_ptr<SimCanNodes> nodes_;
  std::unique_ptr<CanRobot> adapter_;
};

}  // namespace haptel::vehicles
