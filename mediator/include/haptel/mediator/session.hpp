#pragma once
/// @file One grand-prix session on the operator side.
///
/// Threads: the servo loop (1 kHz, HAL), DDS callbacks (state, video), the
/// video decoder, and the session loop (this one, `session_rate_hz`): it
/// feeds the automatic operator, runs the interface, sends commands at the
/// interface's command rate, times the lap and watches the vehicle.
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>

#include "haptel/config/calibration.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/recorder.hpp"

namespace haptel::mediator {

struct SessionSetup {
  RunConfig run;
  TrackConfig track;
  VehicleConfig vehicle;
  GestureConfig gesture;
  DeviceConfig device;
  /// How the device's units map to SI (from device.calibration, or measured
  /// at start-up for the sim device when it has no file).
  DeviceCalibration calibration;
  /// Gravity compensation grid (from device.gravity; empty: none).
  std::optional<GravityGridData> gravity;
  /// haptel-vehicle to spawn; empty: the vehicle runs elsewhere, do not spawn.
  std::filesystem::path vehicle_program;
  bool progress = true;  ///< progress lines on stderr
  /// Record the device's readings here for the `replay` driver (empty: none).
  std::filesystem::path trace;
};

enum class Outcome { kCompleted, kLapCap, kVehicleLost, kVehicleDidNotStart, kInterrupted };
std::string ToString(Outcome outcome);

struct SessionResult {
  Outcome outcome = Outcome::kInterrupted;
  std::string message;  ///< one line: why it ended
  RunRecord record;     ///< everything measured, ready for the recorder
  uint64_t servo_overruns = 0;
  double lost_detect_s = 0.0;  ///< vehicle lost: last state -> detection
};

/// Runs one lap (or until the cap, a lost vehicle or `interrupted`).
SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted);

}  // namespace haptel::mediator
