#pragma once
/// @file The overlay: the text panel (OverlayLines), the HUD's speedometer
/// and indicators, shared control's dial, the person's message and the
/// contact border, over everything in the world. Rasterised on the CPU only
/// when what it shows changes; only the rectangles holding something are
/// blended (a software rasteriser pays for every blended pixel).
#include <string>
#include <vector>

#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class OverlayLayer : public Layer {
 public:
  OverlayLayer(int width, int height, const TexturedQuads& quads);
  ~OverlayLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  /// Redraws the bitmap and its rectangles for `o`, the indicators `lit`.
  void Rasterise(const Overlay& o, const std::vector<std::string>& lines, bool lit);
  void RasterisePanel(const Overlay& o, const std::vector<std::string>& lines);
  void RasteriseSpeedometer(const Overlay& o, bool lit);
  void RasteriseGuidance(const Overlay& o);
  void RasteriseMessage(const Overlay& o);
  void RasteriseContact();

  int width_, height_;
  const TexturedQuads& quads_;
  GLuint texture_ = 0;
  cv::Mat bitmap_;               ///< BGRA, the view's size
  std::string key_;              ///< what bitmap_ shows
  std::vector<cv::Rect> drawn_;  ///< where bitmap_ has anything
};

}  // namespace haptel::view::layers
