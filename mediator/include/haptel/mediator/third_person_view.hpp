#pragma once
/// @file The third-person view (a study's practice lap; haptel run
/// --third-person): the thesis's practice gave the driver a direct view of
/// the robot as well as its camera. Here a chase camera behind the robot's
/// last reported pose renders the track with the operator side's own
/// SyntheticCamera, and the robot's body is drawn into that picture with the
/// projection the predictive display uses (BodySilhouette), so the driver
/// sees the robot among the walls, posts and gates. The view shows it as an
/// inset labelled view::kThirdPersonLabel, never as the robot's camera.
///
/// Only for simulated vehicles (VehicleKindInfo::simulated) on a track: the
/// operator side hands them the track they drive in, so it knows what is
/// around them; for a real robot the track would be a guess.
///
/// The synthetic camera is level (CameraPose's pitch is only for the
/// blimp's course camera), so the chase camera is a level camera
/// kBackLengths body lengths behind the robot and kHeightDiameters body
/// diameters above the floor, with a wide field of view (kFovDeg): the
/// robot, a little below it and ahead, stands in the lower middle of the
/// picture (the shipped robot: its outline from about 68 % to 90 % of the
/// height, the middle fifth of the width), with the track ahead above it.
/// The body is drawn as tall as the camera it carries (`mount_height`), a
/// lighter top face and a white nose towards its heading.
///
/// Threads: the session thread renders (Update) when a new pose has
/// arrived, at most kRate_hz; the view thread takes the latest picture
/// (Latest) under a short lock, as it takes the camera's. The pictures are
/// a few buffers reused once the view has let go of them: no picture is
/// allocated per frame, only its handle (a shared_ptr's control block whose
/// deleter marks the buffer free, with release, when the last copy goes, so
/// Update's acquire load of that mark orders the view's last read of the
/// buffer before the next drawing into it: ThreadSanitizer sees this order,
/// which a fence after use_count() it could not).
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/predictive_display.hpp"
#include "haptel/mediator/robot_predictor.hpp"
#include "haptel/video/frame.hpp"
#include "haptel/video/synthetic_camera.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::mediator {

class ThirdPersonView {
 public:
  /// The chase picture's size (px) and horizontal field of view.
  static constexpr int kWidth = 320;
  static constexpr int kHeight = 240;
  static constexpr double kFovDeg = 90.0;
  /// How far behind the robot's centre the camera is, in body lengths
  /// (diameters), and how high above the floor, in diameters.
  static constexpr double kBackLengths = 3.0;
  static constexpr double kHeightDiameters = 1.5;
  /// At most this many pictures a second (the vehicle's states come faster).
  static constexpr double kRate_hz = 30.0;

  /// Keeps a reference to `track`, which must outlive the view. `vehicle`:
  /// its body's radius and its camera's mount height (the body's height).
  ThirdPersonView(const Track& track, const VehicleConfig& vehicle);

  /// The chase camera's pose behind a robot at `robot`.
  video::CameraPose ChasePose(const PredictedPose& robot) const;
  /// The chase camera's lens (its pose and projection) behind `robot`.
  video::LevelCamera Lens(const PredictedPose& robot) const;

  /// Renders the view behind `robot` into `image` (CV_8UC3, kWidth×kHeight;
  /// its buffer reused when it has that size): the track, then the robot's
  /// body over it.
  void Render(const PredictedPose& robot, cv::Mat& image);

  /// Session thread: renders behind `robot` into a picture the view does not
  /// hold and makes it the latest. False when every picture was held (the
  /// view keeps the one before).
  bool Update(const PredictedPose& robot);
  /// View thread: the latest picture (no image before the first Update).
  video::Frame Latest() const;

  /// The chase camera's configuration (size, field of view, height).
  const CameraConfig& camera() const { return chase_; }
  double body_height_m() const { return body_height_m_; }

 private:
  static constexpr int kBuffers = 4;  ///< the latest, the view's, one being drawn, one spare
  /// One buffer; `free` once no handle to it is left (set by the handle's
  /// deleter, wherever the last copy is dropped).
  struct Picture {
    cv::Mat image;
    std::atomic<bool> free{true};
  };
  CameraConfig chase_;
  double radius_m_;
  double body_height_m_;
  video::SyntheticCamera renderer_;
  BodySilhouette silhouette_;
  std::array<view::PicturePoint, view::Prediction::kOutlineMax> outline_{};
  std::vector<cv::Point> pixels_;
  std::array<std::shared_ptr<Picture>, kBuffers> buffers_;
  mutable std::mutex mutex_;  ///< guards latest_ and id_
  std::shared_ptr<const cv::Mat> latest_;
  uint64_t id_ = 0;
};

/// Whether haptel run --third-person can be given for `vehicle`: a
/// simulated robot (its track is the operator side's). Empty when it can;
/// otherwise one line saying why, for the usage error.
std::string ThirdPersonProblem(const VehicleConfig& vehicle);

}  // namespace haptel::mediator
