#pragma once
/// @file The predictive display's ghost (haptel run --predict): where the
/// vehicle is by its model and its path ahead, drawn in the picture's own
/// pixels on the CPU and laid on the screen over the picture. Only the
/// rectangle holding it is cleared, uploaded and blended.
#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class GhostLayer : public Layer {
 public:
  GhostLayer(const VideoScreen& screen, const TexturedQuads& quads);
  ~GhostLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  const VideoScreen& screen_;
  const TexturedQuads& quads_;
  GLuint texture_ = 0;
  cv::Mat ghost_;   ///< BGRA, the video picture's size
  cv::Rect drawn_;  ///< where the last ghost is in ghost_
};

}  // namespace haptel::view::layers
