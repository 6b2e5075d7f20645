#pragma once
/// @file The Lego-style robot on a CAN bus: two ODrive motor controllers
/// (CAN Simple, one per wheel) and a bumper I/O node, driven by the vehicle
/// node's control loop.
///
/// At start it puts both axes in velocity control with the velocity ramp and
/// requests closed loop; it then sends each wheel's velocity at
/// `can.command_rate_hz`. It watches every node's heartbeat (silent for 3
/// periods: stop, report) and each axis's error (decoded, stop, report);
/// error frames are counted (bus-off stops the robot). Stop() — the node's
/// command watchdog — sends zero velocity, then idle. A fault stays until
/// ClearErrors(): the ODrives' clear-errors command is only ever sent then.
///
/// Time is the sum of Update's dt, so tests drive it frame by frame. Frames
/// that do not decode (wrong length, unknown id, non-finite floats) are
/// counted and dropped.
#include <array>
#include <memory>
#include <string>

#include "haptel/config/vehicle.hpp"
#include "haptel/vehicles/adapter.hpp"
#include "haptel/vehicles/can_bus.hpp"
#include "haptel/vehicles/candump_log.hpp"
#include "haptel/vehicles/kind_report.hpp"

namespace haptel::vehicles {

struct CanCounters {
  uint64_t sent = 0;
  uint64_t send_failed = 0;  ///< the bus's queue was full
  uint64_t received = 0;
  uint64_t malformed = 0;  ///< wrong length, non-finite values: dropped
  uint64_t unknown = 0;    ///< ids of no known node or command: dropped
  uint64_t error_frames = 0;
  uint64_t bus_off = 0;
  uint64_t error_passive = 0;
  uint64_t restarted = 0;  ///< the controller restarted after bus-off
  uint64_t heartbeats = 0;
  uint64_t faults = 0;  ///< times the robot stopped itself
};

class CanRobot final : public VehicleAdapter {
 public:
  /// Takes the bus. `log` (may be null) receives every frame sent and
  /// received; log_status() says how it fares (a failed write ends the log,
  /// not the driving). Validates config.can (ConfigFieldError).
  CanRobot(std::unique_ptr<CanBus> bus, const VehicleConfig& config,
           std::unique_ptr<CandumpWriter> log = nullptr);

  void SetMotors(const models::MotorLevels& levels) override;
  /// Zero velocity now, then both axes idle; the next non-zero SetMotors
  /// requests closed loop again.
  void Stop() override;
  void Update(double dt) override;
  AdapterState State() const override { return state_; }

  /// Clears the ODrives' errors (CAN Simple 0x018) and the adapter's fault,
  /// then starts again (closed loop). The only way out of a fault.
  void ClearErrors();

  /// Hands one received frame to the decoder, as Update does for each frame
  /// off the bus (replaying a recorded log).
  void Decode(const can_frame& frame);

  const CanCounters& counters() const { return counters_; }
  /// Wheel velocity set-points now (turn/s, as sent: right reversed).
  double left_turns_per_s() const { return wheel_cmd_[0]; }
  double right_turns_per_s() const { return wheel_cmd_[1]; }
  /// The last heartbeat's axis state of each wheel (0 before any).
  uint32_t axis_state(int wheel) const { return axis_state_[static_cast<size_t>(wheel)]; }
  double time_s() const { return t_s_; }
  const CandumpWriter* log() const { return log_.get(); }
  /// How the bus log fares, as of the last Update (path "": none kept).
  const CanLogStatus& log_status() const { return log_status_; }

 private:
  void Send(const can_frame& frame);
  void StartAxes();
  void Fault(const std::string& message);
  /// The log's figures and failure into log_status_.
  void UpdateLogStatus();
  double LevelTurns(int level) const;

  std::unique_ptr<CanBus> bus_;
  CanConfig can_;
  double track_width_;
  std::unique_ptr<CandumpWriter> log_;
  AdapterState state_;
  CanCounters counters_;
  double t_s_ = 0.0;
  double next_command_s_ = 0.0;
  bool started_ = false;               ///< closed loop requested
  bool bus_lost_ = false;              ///< the bus is gone: nothing more is sent
  bool idle_ = false;                  ///< Stop() put the axes in idle
  std::array<double, 2> wheel_cmd_{};  ///< turn/s, left and right as sent
  std::array<double, 2> wheel_vel_{};  ///< turn/s from the encoders, as reported
  /// Last heartbeat per node: left, right, io (< 0: none yet).
  std::array<double, 3> last_heartbeat_s_{-1.0, -1.0, -1.0};
  std::array<uint32_t, 2> axis_state_{};
  CanLogStatus log_status_;
};

/// The robot's bus log on haptel/<vehicle>/can_log (link::CanLogWriter,
/// latched), published when it changes. `robot` must outlive it (the node
/// owns both, the report destroyed first).
std::unique_ptr<KindReport> MakeCanLogReport(const CanRobot& robot);

}  // namespace haptel::vehicles
