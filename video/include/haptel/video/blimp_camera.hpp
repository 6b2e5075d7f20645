#pragma once
/// @file The simulated blimp's pilot camera: a synthetic first-person view of
/// a blimp course (BlimpCourseConfig) from a 3-D pose with a pan/tilt head.
///
/// A pinhole camera at (x, y, z), turned by the body's yaw, pitch and roll
/// and then by the head's pan and tilt, with the configured horizontal field
/// of view. It draws, back to front: sky and ground split at the true horizon,
/// a ground grid whose lines fade with distance (motion and height show), the
/// start pad and the landing zone, then the buildings and the gates' frames as
/// shaded boxes sorted far to near (painter's algorithm), each gate numbered
/// (1, 2, ... in course order) above its frame. Every gate has the same
/// colour: the camera cannot know which one is next. Everything 3-D is clipped
/// against the near plane and the sides of the view before it is projected.
/// A camera that zooms (zoom_max > 1) narrows its field of view by the
/// pose's zoom (ZoomedFovDeg) and says it in a line at the bottom left
/// ("SURV 4.0x"); a gate's number, drawn only once it is 7 px tall, shows
/// from afar only zoomed in.
/// Plain OpenCV drawing, no GPU: a 640x480 frame costs about a millisecond.
#include <Eigen/Core>
#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/synthetic_camera.hpp"

namespace haptel::video {

class BlimpCourseCamera {
 public:
  /// Copies what it needs of `course` (it need not outlive the camera) and
  /// draws it as given (LoadBlimpCourse validates a course file; the camera
  /// does not check the course again).
  /// Validates `config` first (CameraConfig::ValidateOrThrow: ConfigFieldError).
  /// `config.mount_height` is not used: the pose's z is the camera's height.
  BlimpCourseCamera(const BlimpCourseConfig& course, const CameraConfig& config);

  /// Renders the view from `pose` into `image` (CV_8UC3, BGR, config size):
  /// position x, y, z; body attitude heading, pitch, roll; head pan, tilt.
  /// Reuses `image`'s buffer when it already has the right size and type.
  /// No state is kept between calls: concurrent calls on one camera are safe.
  /// A non-finite pose, or one farther than 1e6 m out, gives a uniform dark
  /// grey image.
  void Render(const CameraPose& pose, cv::Mat& image) const;

  int width() const { return config_.width; }
  int height() const { return config_.height; }

  /// A box drawn with shaded faces: a building, or one bar of a gate's frame.
  struct Box {
    Eigen::Vector3d centre;
    Eigen::Vector3d axis_a;                  ///< unit, horizontal
    Eigen::Vector3d axis_b;                  ///< unit, horizontal, +z x axis_a
    Eigen::Vector3d half;                    ///< half extents along axis_a, axis_b and z, m
    std::array<Eigen::Vector3d, 8> corners;  ///< bit 0: +a, bit 1: +b, bit 2: +z
    std::array<cv::Vec3d, 6> face_colour;    ///< lit, per face (+a, -a, +b, -b, +z, -z)
    int label = 0;                           ///< gate number drawn above it; 0: none
    Eigen::Vector3d label_centre{0.0, 0.0, 0.0};
    double label_height = 0.0;  ///< m
    /// The number, drawn once: per pixel, outline and fill coverage (CV_8UC2),
    /// scaled onto the frame when drawn (putText allocates per call).
    cv::Mat label_mask;
  };
  /// A flat convex polygon on the ground (z = 0): start pad, landing zone.
  struct GroundPolygon {
    static constexpr int kMaxVertices = 32;
    std::array<Eigen::Vector3d, kMaxVertices> vertices;
    int count = 0;
    cv::Vec3d colour;
    Eigen::Vector3d centre;
  };

 private:
  CameraConfig config_;
  /// A zoom lens's overlay names it: its name's first four letters, upper case.
  std::string overlay_name_;
  std::vector<Box> boxes_;
  std::vector<GroundPolygon> ground_;
};

/// The synthetic first-person view of a blimp course (BlimpCourseCamera).
class BlimpCourseSource final : public CameraSource {
 public:
  BlimpCourseSource(const BlimpCourseConfig& course, const CameraConfig& config)
      : camera_(course, config) {}
  bool Grab(const CameraPose& pose, cv::Mat& bgr_out) override {
    camera_.Render(pose, bgr_out);
    return true;
  }
  std::string Describe() const override { return "synthetic"; }
  bool RendersAtGrab() const override { return true; }

 private:
  BlimpCourseCamera camera_;
};

/// The source `config.source` names, for a blimp: kSynthetic renders `course`
/// (BlimpCourseSource); kDevice and kFile are what MakeCameraSource makes for
/// them (CaptureCamera), with the same errors. `config_file` names the
/// vehicle config file in error messages.
std::unique_ptr<CameraSource> MakeBlimpCameraSource(const CameraConfig& config,
                                                    const BlimpCourseConfig& course,
                                                    const std::string& config_file);

}  // namespace haptel::video
