#pragma once
/// @file What the predictive display shows (haptel run --predict on), as
/// the view's flat data (view::Prediction, view::TrackMap): the robot's
/// ghost where its model says it is now and its path ahead with the command
/// being given, projected into the camera picture being shown, and the same
/// on a map of the track beside the vehicle as last reported.
///
/// The camera pose the ghost is projected from is the newest state's: the
/// vehicle samples its pose and grabs its picture at the same rate and
/// sends both over the same link, so the picture being shown and the newest
/// state are about equally old (within a frame period, 33 ms at 30 Hz). The
/// projection is the vehicle camera's own (video::LevelCamera, with the
/// field of view, picture size and mount height of the vehicle's file), so
/// the ghost stands on the floor the picture shows.
///
/// The ghost is the robot's body: an upright cylinder of `body.radius`. Its
/// silhouette is drawn, not just its footprint, because the camera does not
/// see the floor near itself (the shipped 55° camera 0.12 m up sees it from
/// 0.31 m on), where a ghost a few hundred milliseconds ahead stands. The
/// vehicle file gives no height, so the ghost is as tall as it can be while
/// a ghost with no lead (where the camera is) stays below the picture, as
/// the robot's own body does (kHeightMargin of that height, at most the
/// camera's): then the smallest lead shows, rising into the bottom of the
/// picture as far as the vehicle is ahead of its video (the shipped camera:
/// a 6.9 cm ghost, in sight from a lead of 2 cm).
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/blimp_predictor.hpp"
#include "haptel/mediator/robot_predictor.hpp"
#include "haptel/video/camera_projection.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::mediator {

/// The robot's body, an upright cylinder standing on the floor, as a level
/// camera sees it: its footprint clipped to what lies in front of the camera
/// (the clipping planes are upright, so the clipped footprint is the clipped
/// cylinder's section at every height), and its silhouette, the convex hull
/// of that section's corners at the floor and at its top. The predictive
/// display draws its ghost with it, the practice lap's third-person view
/// the robot (third_person_view.hpp). Allocates nothing once its buffers
/// have grown.
class BodySilhouette {
 public:
  /// Footprint corners of the cylinder.
  static constexpr int kSides = 24;

  BodySilhouette();

  /// The silhouette of a body of `radius` and `height` (m) standing at
  /// (x, y), seen by `camera` (whose picture is `width`×`height_px`
  /// pixels), into `out` as picture fractions; returns how many corners (0:
  /// out of the camera's sight, or behind it).
  int Make(const video::LevelCamera& camera, double width, double height_px, double x, double y,
           double radius, double height,
           std::array<view::PicturePoint, view::Prediction::kOutlineMax>& out);

  /// The footprint as Make last clipped it, camera coordinates (depth,
  /// lateral): its top face is this at the body's height.
  const std::vector<cv::Vec2d>& footprint() const { return footprint_; }

 private:
  std::vector<cv::Vec2d> footprint_, scratch_;
  std::vector<cv::Point2f> corners_, hull_;
};

class PredictiveDisplay {
 public:
  /// Footprint corners of the ghost's cylinder.
  static constexpr int kSides = BodySilhouette::kSides;
  /// The ghost's height as a share of the tallest that a ghost with no
  /// lead keeps out of the picture.
  static constexpr double kHeightMargin = 0.9;

  PredictiveDisplay(const CameraConfig& camera, double body_radius);

  /// What the view draws, into `out`: the ghost at `path`'s first pose (the
  /// vehicle now, RobotPredictor::PathAhead), the path ahead through the
  /// rest, seen from `camera_pose` (the newest state's pose: the picture's);
  /// on the map, `camera_pose` as last reported. Allocates nothing once its
  /// buffers have grown.
  void Make(const PredictedPose& camera_pose, const std::vector<PredictedPose>& path,
            double one_way_delay_s, view::Prediction& out);

  double ghost_height_m() const { return ghost_height_m_; }

 private:
  CameraConfig camera_;
  double radius_m_;
  double ghost_height_m_;
  BodySilhouette silhouette_;
};

/// The map's geometry of `track`: walls, the start line across the
/// corridor, each gate from post to post, the posts and round obstacles.
view::TrackMap TrackMapOf(const Track& track);

/// The blimp's predictive display, on the course map only: the blimp as
/// last reported (`reported`), the ghost at `path`'s first pose (the blimp
/// now, BlimpPredictor::PathAhead) and its path ahead, each with its height,
/// which the map says in words (it is seen from above). Nothing goes into the
/// picture: the pilot camera hangs under the hull, so a ghost a few hundred
/// milliseconds ahead (at 2 m/s, under a metre) would surround the camera
/// rather than stand in front of it. `hull_length`: the map draws the hull
/// as a disc of half that. Allocates nothing.
void MakeBlimpPrediction(const BlimpPredictedPose& reported,
                         const std::vector<BlimpPredictedPose>& path, double hull_length,
                         double one_way_delay_s, view::Prediction& out);

/// The blimp course's map: each gate across its opening from post to post,
/// labelled with the opening's heights above the ground; each building's
/// footprint (as walls); the start; the landing circle.
view::TrackMap CourseMapOf(const BlimpCourseConfig& course);

}  // namespace haptel::mediator
