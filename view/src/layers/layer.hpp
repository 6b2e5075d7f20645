#pragma once
/// @file A layer of the operator's view: one thing drawn (the world's shapes,
/// the video screen, the ghost, the overlay, the third-person inset, the
/// fleet's tiles, the map), with its own GL objects and cached bitmaps,
/// created at start-up. The Renderer draws its layers in order, each over
/// the ones before; the list is built in one place (MakeLayers, renderer.cpp).
#include <Eigen/Geometry>
#include <array>

#include "haptel/view/renderer.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::view::layers {

/// One frame as every layer sees it: the framebuffer, the camera, the clock.
struct Frame {
  int width = 0;   ///< the framebuffer, pixels
  int height = 0;  ///< the framebuffer, pixels
  /// Device frame to clip space, the view turned by a tracked gaze.
  Eigen::Matrix4f view_projection = Eigen::Matrix4f::Identity();
  double t_s = 0.0;  ///< the run's clock: the indicators flash on it
};

/// The virtual screen the video hangs on, shared by the layers drawn on or
/// around it (the world's bezel and stand, the picture, the ghost) and by
/// the Renderer's queries (ScreenCorners). The screen layer sets the
/// picture's size; the Renderer sets the turn each frame.
struct VideoScreen {
  ScreenPlacement placement;
  double aspect = 3.0 / 4.0;  ///< height / width of the picture (4:3 until the first)
  int picture_cols = 0;       ///< the picture as uploaded (0: none yet)
  int picture_rows = 0;
  /// About the eye, with a tracked gaze: where the vehicle camera points.
  Eigen::Quaternionf turn = Eigen::Quaternionf::Identity();

  /// The screen's centre, turned.
  std::array<double, 3> Centre() const { return AboutEyeOf(placement.centre); }
  /// The screen's orientation (w, x, y, z): the turn.
  std::array<double, 4> Orientation() const { return {turn.w(), turn.x(), turn.y(), turn.z()}; }
  /// `point` turned about the eye with the screen.
  std::array<double, 3> AboutEyeOf(const std::array<double, 3>& point) const;
  /// The textured unit quad (gl_kit's screen quad) onto the screen.
  Eigen::Matrix4f QuadModel() const;
};

/// Owns GL objects: neither copied nor moved.
class Layer {
 public:
  Layer() = default;
  virtual ~Layer() = default;
  Layer(const Layer&) = delete;
  Layer& operator=(const Layer&) = delete;
  /// Draws this layer of `model` over what the layers before it drew. Sets
  /// the GL state it needs (program, depth test, blending); its GL objects
  /// are made once, in its constructor, never per frame.
  virtual void Draw(const ViewModel& model, const Frame& frame) = 0;
};

}  // namespace haptel::view::layers
