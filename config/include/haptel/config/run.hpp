#pragma once
/// @file The operator side's run configuration (config/haptel.yaml).
#include <filesystem>
#include <string>

#include "haptel/config/link.hpp"

namespace haptel {

/// The automatic operator: a simulated person driving through the interface.
struct OperatorConfig {
  double reaction_delay_s = 0.15;
  double arm_time_constant_s = 0.1;  ///< lag of the hand target behind intent
  double lookahead = 0.35;           ///< pure-pursuit look-ahead, m
  double cruise = 0.9;               ///< forward command on straights (0..1)
  double min_forward = 0.35;         ///< forward command in the tightest turn
  double slow_radius = 0.15;         ///< turn radius at which it slows to min_forward, m
  double muscle_stiffness = 250.0;   ///< N/m
  double muscle_damping = 12.0;      ///< N·s/m
  double muscle_max_force = 8.0;     ///< N
  double muscle_integral_gain = 400.0;  ///< N/(m·s): pushing harder against a pull
  double backoff_s = 0.8;            ///< reverse this long after a bumper contact
};

/// The simulated arm of the haptic device (per side).
struct SimDeviceConfig {
  double arm_mass = 0.8;       ///< kg moved by operator and device
  double damping = 1.0;        ///< N·s/m of joint friction
  double force_limit = 7.0;    ///< N at the wrist
};

struct ServoConfig {
  double rate_hz = 1000.0;
  int realtime_priority = 80;  ///< SCHED_FIFO priority when the process may
};

struct RunConfig {
  std::filesystem::path file;
  std::string name = "default";
  std::filesystem::path track;
  std::filesystem::path vehicle;
  std::string interface = "gesture";
  std::filesystem::path interfaces_dir;  ///< where <interface>.yaml files live
  std::filesystem::path database = "runs/haptel.db";
  double vehicle_timeout_s = 0.5;  ///< no state for this long: vehicle lost
  double session_rate_hz = 100.0;
  bool video_decode = true;
  OperatorConfig op;
  SimDeviceConfig device;
  ServoConfig servo;
  LinkConfig link;
};

RunConfig LoadRun(const std::filesystem::path& file);

/// The interface file for a name: `<interfaces_dir>/<name>.yaml`. Throws
/// ConfigError listing the available names when there is none.
std::filesystem::path InterfaceFile(const RunConfig& run, const std::string& name);

}  // namespace haptel
