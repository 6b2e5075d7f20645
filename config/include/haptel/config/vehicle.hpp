#pragma once
/// @file A vehicle node's configuration.
#include <filesystem>
#include <string>

#include "haptel/config/link.hpp"

namespace haptel {

/// Differential drive of the Lego-style tank: each motor takes a signed speed
/// level, as the brick does; commands are quantised to these levels.
struct DriveConfig {
  int speed_levels = 8;              ///< levels in each direction
  double max_speed = 0.3;            ///< tread speed at the top level, m/s
  double track_width = 0.16;         ///< distance between treads, m
  double motor_time_constant = 0.08; ///< first-order motor lag, s
  double left_gain = 1.0;            ///< per-motor gain: uneven turning
  double right_gain = 0.95;
};

struct BodyConfig {
  double radius = 0.11;  ///< collision circle, m
  /// Contacts within this angle of straight ahead press the front bumper.
  double bumper_half_angle_deg = 70.0;
  /// Contacts within this angle of straight ahead press both switches.
  double bumper_both_deg = 8.0;
};

struct CameraConfig {
  double rate_hz = 15.0;
  int width = 320;
  int height = 240;
  double fov_deg = 55.0;    ///< horizontal, webcam-like
  int jpeg_quality = 80;
  double mount_height = 0.12;  ///< m above the floor
};

struct VehicleConfig {
  std::filesystem::path file;
  std::string name = "robot1";
  std::string kind = "sim-robot";
  std::filesystem::path world;  ///< track the simulator drives on
  double sim_rate_hz = 200.0;
  double state_rate_hz = 50.0;
  double watchdog_timeout_s = 0.25;
  DriveConfig drive;
  BodyConfig body;
  CameraConfig camera;
  LinkConfig link;
};

VehicleConfig LoadVehicle(const std::filesystem::path& file);

}  // namespace haptel
