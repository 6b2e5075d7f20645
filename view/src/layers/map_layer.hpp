#pragma once
/// @file The predictive display's map (haptel run --predict on a track with
/// a map), top right: the track drawn to scale once, north up, and each
/// frame over it the vehicle as last reported, as predicted now and its
/// path ahead (with a flying vehicle's heights).
#include "gl_kit.hpp"
#include "layer.hpp"

namespace haptel::view::layers {

class MapLayer : public Layer {
 public:
  explicit MapLayer(const TexturedQuads& quads);
  ~MapLayer() override;

  void Draw(const ViewModel& model, const Frame& frame) override;

  /// Where a track point (m) lands on the map as last drawn: pixels from the
  /// view's top-left corner. False when the last frame drew no map.
  bool MapPoint(double x, double y, double& px, double& py) const;

 private:
  /// Draws the track and the legend into track_ (panel-sized, `side` the
  /// map's square) and fits the track into it.
  void RasteriseTrack(const TrackMap& map, const cv::Size& panel, int side, const Frame& frame);
  /// Draws the poses, the path and the legend's figures over the track.
  void RasterisePoses(const Prediction& pr, int side, const Frame& frame);
  /// A track point as a sub-pixel point of the panel.
  cv::Point PanelPoint(double x, double y) const;

  const TexturedQuads& quads_;
  GLuint texture_ = 0;
  cv::Mat track_;                       ///< BGRA, the panel's size: the track and legend
  cv::Mat map_;                         ///< the track with this frame's poses over it
  const TrackMap* track_of_ = nullptr;  ///< the track track_ shows
  cv::Rect panel_;                      ///< where the panel is, view pixels
  double scale_ = 0, ox_ = 0, oy_ = 0;  ///< track metres to panel pixels
  bool drawn_ = false;                  ///< in the last frame
};

}  // namespace haptel::view::layers
