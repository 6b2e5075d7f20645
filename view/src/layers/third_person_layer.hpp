#pragma once
/// @file The third-person view (a practice lap; haptel run --third-person):
/// a chase camera's picture of the robot, as an inset on the left under the
/// overlay's panel (ThirdPersonRect), framed and labelled kThirdPersonLabel
/// so nobody takes it for the robot's camera. The frame and label are
/// rasterised once; the picture is uploaded only when a new one comes.
#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class ThirdPersonLayer : public Layer {
 public:
  ThirdPersonLayer(int width, int height, const TexturedQuads& quads);
  ~ThirdPersonLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  const TexturedQuads& quads_;
  cv::Rect frame_rect_;       ///< the frame around the label and picture, view pixels
  cv::Rect picture_rect_;     ///< the picture, view pixels
  GLuint frame_texture_ = 0;  ///< the frame and its label, BGRA
  GLuint picture_texture_ = 0;
  int picture_cols_ = 0, picture_rows_ = 0;  ///< as uploaded
  uint64_t shown_id_ = 0;
};

}  // namespace haptel::view::layers
