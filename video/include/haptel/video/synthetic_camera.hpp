#pragma once
/// @file A synthetic first-person camera for simulated vehicles.
///
/// Renders what a webcam on the robot would see of a Track: sky above the
/// horizon, floor below it, the corridor walls as vertical panels, gate posts
/// and round obstacles as vertical bars — with a narrow, webcam-like field of
/// view. Plain OpenCV drawing, no GPU: a 640x480 frame costs about a
/// millisecond of CPU, its JPEG encode a little less (`haptel bench skip`).
#include <cstdint>
#include <opencv2/core.hpp>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/camera_aim.hpp"

namespace haptel::video {

/// Camera position (m, world frame: x east, y north, z up) and orientation.
/// The robot's SyntheticCamera uses x, y, heading plus pan, and zoom only
/// (its camera is level, `mount_height` above the floor); the 3-D fields, all 0 by default,
/// are for flying vehicles (video::BlimpCourseCamera).
struct CameraPose {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;  ///< body yaw, rad, counter-clockwise from +x
  double z = 0.0;        ///< height of the camera above the ground, m
  double pitch = 0.0;    ///< body attitude, rad: nose up positive
  double roll = 0.0;     ///< body attitude, rad: right side down positive
  double pan = 0.0;      ///< camera head relative to the body, rad: look left positive
  double tilt = 0.0;     ///< camera head relative to the body, rad: look up positive
  /// The lens's zoom: the field of view is the camera's fov_deg narrowed by
  /// it (ZoomedFovDeg); 1: the widest.
  double zoom = 1.0;
  /// The last command that steered the camera (VideoFrame.command_seq; 0: none).
  uint64_t command_seq = 0;
};

/// Where camera `camera` looks from a vehicle at `body` (the family's
/// CameraPoseOf), aimed at `aim`: moved by its mount (ahead, left; its
/// height is the body's z for a flying vehicle), its head turned by the
/// mount's yaw and pitch plus the aim's pan and tilt, zoomed by the aim.
CameraPose MountedPose(const CameraPose& body, const CameraConfig& camera, const CameraAim& aim);

class SyntheticCamera {
 public:
  /// Keeps a reference to `track`, which must outlive the camera. Validates
  /// `config` first (CameraConfig::ValidateOrThrow: ConfigFieldError).
  SyntheticCamera(const Track& track, const CameraConfig& config);

  /// Renders the view from `pose` into `image` (CV_8UC3, BGR, config size).
  /// Reuses `image`'s buffer when it already has the right size and type.
  void Render(const CameraPose& pose, cv::Mat& image) const;

  int width() const { return config_.width; }
  int height() const { return config_.height; }

 private:
  const Track& track_;
  CameraConfig config_;
};

}  // namespace haptel::video
