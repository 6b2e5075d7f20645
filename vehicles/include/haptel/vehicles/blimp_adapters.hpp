#pragma once
/// @file The blimp's adapters, one per vehicle kind:
///
/// - "sim-blimp": the simulated airship (SimBlimp) flown directly;
/// - "servo-blimp": the real blimp's seven channels through its USB servo
///   controller (Maestro or SC-8000) on a serial port — the adapter knows
///   only what it sent and the controller's error register, no pose;
/// - "servo-blimp-sim": that same adapter code on one end of a
///   pseudo-terminal, a simulated servo controller on the other end decoding
///   the bytes as the device would, and its pulse widths flying SimBlimp.
#include <array>
#include <memory>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/models/sim_blimp.hpp"
#include "haptel/servo/serial_port.hpp"
#include "haptel/servo/servo_output.hpp"
#include "haptel/servo/sim_servo_controller.hpp"
#include "haptel/vehicles/blimp_adapter.hpp"

namespace haptel::vehicles {

/// A command's seven channels as fractions of their travel ([-1, 1]; power
/// [0, 1]), in BlimpChannel order: the camera's angles over its range.
std::array<double, kBlimpChannels> ChannelValues(const BlimpCommand& command);
/// The inverse: channel fractions back to a command.
BlimpCommand CommandFromChannels(const std::array<double, kBlimpChannels>& values);

/// The airship a reality flies (config/reality.hpp): the file's with the
/// reality's steady wind and gusts, envelope volume (buoyancy) and payload
/// (the heavier gondola). NominalReality gives `airship` back unchanged.
AirshipConfig AirshipInReality(const AirshipConfig& airship, const DrawnReality& reality);

class SimBlimpAdapter final : public BlimpAdapter {
 public:
  /// Flies the file's airship in `reality` (AirshipInReality; the twin with
  /// NominalReality); the state says nothing of the wind, only where the
  /// blimp is and its airspeed.
  SimBlimpAdapter(const AirshipConfig& airship, const BlimpCourseConfig& course,
                  const DrawnReality& reality);
  void Apply(const BlimpCommand& command) override { command_ = command; }
  void Update(double dt) override { sim_.Step(dt, command_); }
  BlimpAdapterState State() const override;
  const DrawnReality* reality() const override { return &reality_; }
  bool Truth(TruthRow* row) const override;
  const models::SimBlimp& sim() const { return sim_; }

 private:
  DrawnReality reality_;
  models::SimBlimp sim_;
  BlimpCommand command_;
};

/// Fills the pose part of `state` from the simulator.
void PoseFromSim(const models::SimBlimp& sim, BlimpAdapterState& state);
/// Where the simulated blimp truly is: its yaw as the heading, its
/// horizontal ground speed and its yaw rate (world z).
void TruthFromSim(const models::SimBlimp& sim, TruthRow* row);

/// The real blimp's channels through its servo controller. A Maestro judged
/// untrustworthy (ServoOutput::untrusted(): its errors, its silence or stray
/// bytes, poll after poll) is a fault for good: from then on every channel
/// is held at neutral whatever is commanded, and the state carries the fault
/// with the reason naming the errors (the operator's run ends as vehicle
/// lost); the controller's own timeout takes over if even that is not heard.
class ServoBlimpAdapter final : public BlimpAdapter {
 public:
  /// `config` validated; `port` opened (SerialPort). Sends the neutral
  /// pulses first.
  ServoBlimpAdapter(const ServoControllerConfig& config, std::unique_ptr<servo::ByteStream> port);
  /// Sets the channels; neutral whatever `command` says once the controller
  /// is untrusted.
  void Apply(const BlimpCommand& command) override;
  /// Sends the pulses every kSendPeriod_s and polls the controller's
  /// errors; the poll that finds the controller untrusted puts every
  /// channel to neutral at once. Throws servo::SerialLost when the port has
  /// vanished.
  void Update(double dt) override;
  BlimpAdapterState State() const override;
  /// The camera's axes that have servos (config.camera_channels) to their
  /// pulses; neutral once the controller is untrusted.
  void AimCamera(size_t camera, const CameraAim& aim) override;
  const servo::ServoOutput& output() const { return output_; }

  /// How often the pulses go out: every channel's target at 50 Hz, the
  /// servos' own frame rate (an SC-8000 at 9600 baud takes 53 frames/s).
  static constexpr double kSendPeriod_s = 0.02;

 private:
  ServoControllerConfig config_;
  servo::ServoOutput output_;
  BlimpCommand applied_;
  std::array<double, kBlimpChannels> pulse_us_{};
  double time_s_ = 0.0;
  double next_send_s_ = 0.0;
};

class SimulatedServoBlimp final : public BlimpAdapter {
 public:
  SimulatedServoBlimp(const ServoControllerConfig& config, const AirshipConfig& airship,
                      const BlimpCourseConfig& course, const DrawnReality& reality);
  void Apply(const BlimpCommand& command) override { adapter_->Apply(command); }
  void AimCamera(size_t camera, const CameraAim& aim) override { adapter_->AimCamera(camera, aim); }
  /// The camera's axes as the simulated controller's outputs hold them.
  bool CameraAimed(size_t camera, CameraAim* aim) const override;
  void Update(double dt) override;
  BlimpAdapterState State() const override;
  const DrawnReality* reality() const override { return &reality_; }
  bool Truth(TruthRow* row) const override {
    TruthFromSim(sim_, row);
    return true;
  }

 private:
  DrawnReality reality_;
  ServoControllerConfig config_;
  servo::PtyPair pty_;
  std::unique_ptr<ServoBlimpAdapter> adapter_;
  std::unique_ptr<servo::SimServoController> controller_;
  models::SimBlimp sim_;
  double time_s_ = 0.0;
};

}  // namespace haptel::vehicles
