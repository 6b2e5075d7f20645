#pragma once
/// @file The video screen: the vehicle's latest picture on the virtual
/// screen in front of the operator (thesis fig. 8.4), uploaded only when a
/// new one comes; dark grey before the first.
#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class ScreenLayer : public Layer {
 public:
  /// Sets `screen`'s picture size and aspect as pictures come.
  ScreenLayer(VideoScreen& screen, const TexturedQuads& quads);
  ~ScreenLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  VideoScreen& screen_;
  const TexturedQuads& quads_;
  GLuint texture_ = 0;
  uint64_t shown_id_ = 0;  ///< the picture uploaded last
};

}  // namespace haptel::view::layers
