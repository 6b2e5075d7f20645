#pragma once
/// @file The world's shapes, lit from above: a floor, the screen's bezel and
/// stand, then the model's shapes (hands, controls, scene bodies, the
/// gesture wall). Drawn first, with depth, so the screen's picture and the
/// ghost hide behind a hand in front of them.
#include <vector>

#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class WorldLayer : public Layer {
 public:
  explicit WorldLayer(const VideoScreen& screen);
  ~WorldLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  /// Adds `mesh` placed and scaled, in `color`, to the frame's batch.
  void Add(const Mesh& mesh, const std::array<double, 3>& position,
           const std::array<double, 4>& orientation, const Eigen::Vector3f& scale,
           const Rgba& color);
  void AddShape(const Shape& shape);
  /// The floor, and the screen's bezel and stand.
  void AddRoom(bool gaze_tracked);

  const VideoScreen& screen_;
  GLuint program_ = 0;
  GLint mvp_ = -1, light_ = -1;
  Mesh cube_, sphere_, cylinder_;
  /// Lit shapes arrive already in the world frame (the CPU transforms them
  /// into one batch): a software rasteriser's cost per draw call dwarfs its
  /// cost per vertex, so the whole world is one draw.
  GLuint batch_vao_ = 0, batch_vbo_ = 0, batch_ebo_ = 0;
  std::vector<float> batch_;  ///< position, normal, colour: 10 floats a vertex
  std::vector<uint32_t> batch_index_;
};

}  // namespace haptel::view::layers
