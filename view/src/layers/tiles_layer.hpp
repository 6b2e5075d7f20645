#pragma once
/// @file A fleet's tiles (haptel run --fleet): each vehicle's latest picture
/// with its name, state and lap, in a column down the right edge
/// (TileRect), the driven one framed in kTileFrameBgr; and the fleet's line
/// (who is driven, how to switch) at the bottom left. Each is rasterised on
/// the CPU when what it shows changes and uploaded whole (they are small).
#include <string>

#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class TilesLayer : public Layer {
 public:
  TilesLayer(const TexturedQuads& quads);
  ~TilesLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

 private:
  void DrawLine(const Tiles& tiles, const Frame& frame);
  void DrawColumn(const ViewModel& model, int count, const Frame& frame);
  /// Redraws the column's bitmap: every tile, `column` its place in the view.
  void RasteriseColumn(const ViewModel& model, int count, const cv::Rect& column,
                       const Frame& frame);

  const TexturedQuads& quads_;
  GLuint line_texture_ = 0;
  cv::Mat line_;            ///< BGRA, the line's box
  cv::Rect line_box_;       ///< where it goes, view pixels
  std::string line_shown_;  ///< what line_ says
  GLuint column_texture_ = 0;
  cv::Mat column_;          ///< BGRA, the column's size
  std::string column_key_;  ///< every tile's text and picture id, as column_ shows them
  cv::Mat tile_picture_;    ///< a picture scaled to its tile, reused
};

}  // namespace haptel::view::layers
