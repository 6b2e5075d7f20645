#pragma once
/// @file The haptic device part of a session: the device (sim, udp or
/// replay), its calibration, the HAL, gravity compensation, the servo loop
/// and the optional trace of its readings.
///
/// Calibration policy (DeviceCalibrationFor): a real device (`udp`) uses the
/// file `haptel calibrate` wrote, named by the device file's `calibration:`
/// key, and is never calibrated automatically; a missing file, or one
/// measured on another device, is an error naming the command that makes
/// one. The `sim` device without a file is calibrated at start-up, unattended.
/// A device that measures in SI itself (`sdl-ff`, the mouse) gets the identity
/// calibration unless its file names one. A `replay` device uses its file's
/// calibration or the one recorded beside the trace
/// (`<trace>.calibration.yaml`, written by `haptel run --trace`).
#include <filesystem>
#include <memory>
#include <optional>

#include "haptel/config/calibration.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"

namespace haptel::haptics {
class GravityGrid;
class ReplayDevice;
class ServoLoop;
class SimDevice;
class TraceWriter;
}  // namespace haptel::haptics

namespace haptel::mediator {

/// The companion calibration file of a trace.
std::filesystem::path TraceCalibrationFile(const std::filesystem::path& trace);

/// The calibration a session must use for `device`, or nullopt when the sim
/// device is to be calibrated at start-up. Throws ConfigError as described
/// above (naming the device file and `haptel calibrate` or `haptel run --trace`).
std::optional<DeviceCalibration> DeviceCalibrationFor(const DeviceConfig& device);

class HapticSide {
 public:
  /// Opens the device and settles its calibration (see DeviceCalibrationFor;
  /// `calibration` is its answer). `muscle` drives the sim's simulated
  /// operator. `trace`: record the device's readings there (empty: none),
  /// with the calibration beside it; recording starts at StartTrace.
  HapticSide(const DeviceConfig& device, const std::optional<DeviceCalibration>& calibration,
             const std::optional<GravityGridData>& gravity, const OperatorConfig& muscle,
             const std::filesystem::path& trace);
  ~HapticSide();
  HapticSide(const HapticSide&) = delete;
  HapticSide& operator=(const HapticSide&) = delete;

  /// Starts the servo loop; with `progress`, says once what real-time
  /// privileges it could not get.
  void Start(bool progress);
  /// Forces to zero, then stops the servo loop. Safe to call twice.
  void Stop();
  /// One servo cycle of every arm the device has, at `now_ns`: for a caller
  /// that runs the loop in simulated time (tests) instead of Start.
  void Tick(int64_t now_ns);
  /// The vehicle answered: the trace starts recording and a replay starts playing.
  void OnVehicleUp();
  /// Session thread, each tick: whether the session lets the hands drive;
  /// the trace records each change (and the state when it starts), so that
  /// a replay repeats the recorded session's decisions. Allocates nothing.
  void RecordEngaged(int64_t now_ns, bool engaged);

  haptics::Hal& hal() { return *hal_; }
  /// Tells `tap` every servo tick (a session file's recorder; null: none). Before Start.
  void SetServoTap(haptics::ServoTap* tap) { servo_->SetTap(tap); }
  /// The simulated device, for the automatic operator (null for others).
  haptics::SimDevice* sim() { return sim_; }
  /// A replay that has played its whole trace.
  bool replay_finished() const;
  /// An arm the device has (has_side) stopped answering: forces are zero.
  bool lost() const;
  /// When lost because the person unplugged the device (a joystick), the
  /// device's line saying so; else "" (Device::UnpluggedLine).
  std::string unplugged() const { return device_->UnpluggedLine(); }
  /// How long the lost arm has been silent: seconds since its newest wrist
  /// reading (the longest, if both are lost; 0 when none is).
  double silent_s() const;
  LoopStats Stats() const;
  /// The servo loop's counters, summed over the arms the device has. Any thread.
  haptics::ServoCounters Counters() const;
  /// One arm's counters (all zero for an arm the device does not have). Any thread.
  haptics::ServoCounters Counters(haptics::Side side) const;
  /// The servo loop's target rate (the device file's servo.rate_hz).
  double target_hz() const { return config_.servo.rate_hz; }
  /// The servo loop's period distribution (the right arm's when it has one).
  const Histogram& ServoPeriods() const;
  /// Of the same arm: the periods of the ticks that rendered a cue (a fleet's switch).
  const Histogram& ServoCuePeriods() const;
  const DeviceConfig& config() const { return config_; }
  /// What the device measured of the person's use of it (Device::UseReport). Any thread.
  haptics::DeviceUseReport UseReport() const { return device_->UseReport(); }

 private:
  DeviceConfig config_;
  std::unique_ptr<haptics::Device> device_;
  haptics::SimDevice* sim_ = nullptr;
  haptics::ReplayDevice* replay_ = nullptr;
  DeviceCalibration calibration_;
  std::unique_ptr<haptics::Hal> hal_;
  std::unique_ptr<haptics::GravityGrid> gravity_;
  std::unique_ptr<haptics::TraceWriter> trace_;
  int trace_engaged_ = -1;  ///< the engaged state last recorded (-1: none yet)
  std::unique_ptr<haptics::ServoLoop> servo_;
  bool stopped_ = false;
};

}  // namespace haptel::mediator
