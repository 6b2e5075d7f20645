#pragma once
/// @file One grand-prix session on the operator side.
///
/// Threads: the servo loop (1 kHz, HAL), DDS callbacks (state, video), the
/// video decoder, the physics world when the interface has controls (a
/// cockpit: proxy hands, wheel and lever at 1/step_s), and the session loop
/// (this one, `session_rate_hz`): it
/// feeds the automatic operator, runs the interface, sends commands at the
/// interface's command rate, times the lap and watches the vehicle.
#include <atomic>
#include <filesystem>
#include <optional>
#include <string>

#include "haptel/config/calibration.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/recorder.hpp"

namespace haptel::mediator {

struct SessionSetup {
  RunConfig run;
  TrackConfig track;
  VehicleConfig vehicle;
  /// The interface: a cockpit when set, otherwise the gesture interface.
  GestureConfig gesture;
  std::optional<CockpitConfig> cockpit;
  /// The physics world, used only when the interface's controls or the
  /// scene have bodies.
  PhysicsConfig physics;
  /// The haptic scene the hands can touch (none: nothing to touch).
  std::optional<Scene> scene;
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
  /// The physics thread, when there was one (rate 0 otherwise).
  double physics_rate_hz = 0.0;
  double physics_period_p99_us = 0.0;
  double physics_step_max_us = 0.0;
  uint64_t physics_hand_resets = 0;
  int scene_bodies = 0;  ///< scene objects built into the world
  /// Seconds from the start until the operator's hands held the controls
  /// (0 when there was nothing to grasp; negative if they never did).
  double grasp_s = 0.0;
};

/// Runs one lap (or until the cap, a lost vehicle or `interrupted`).
SessionResult RunSession(const SessionSetup& setup, const std::atomic<bool>& interrupted);

}  // namespace haptel::mediator
