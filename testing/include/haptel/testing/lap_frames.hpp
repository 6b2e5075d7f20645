#pragma once
/// @file The synthetic camera's frames along a lap of a track, as a codec
/// test or benchmark needs them: clips driven along the centre line at the
/// robot's pace, spread evenly around the lap (a straight, a bend, a gate...).
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/synthetic_camera.hpp"

namespace haptel::testing {

/// `clips` clips of `frames_per_clip` frames each, rendered by a
/// SyntheticCamera of `camera` driving the centre line at `speed` (m/s) and
/// `camera.rate_hz`; clip k starts k/clips of the way round the lap.
inline std::vector<cv::Mat> LapFrames(const Track& track, const CameraConfig& camera, int clips,
                                      int frames_per_clip, double speed = 0.3) {
  const video::SyntheticCamera renderer(track, camera);
  std::vector<cv::Mat> frames;
  frames.reserve(static_cast<size_t>(clips * frames_per_clip));
  const double step = speed / camera.rate_hz;
  const double start = track.ClosestArcLength(track.StartPosition());
  for (int clip = 0; clip < clips; ++clip) {
    const double clip_start = start + track.length() * clip / clips;
    for (int i = 0; i < frames_per_clip; ++i) {
      const double s = clip_start + step * i;
      const Vec2 at = track.PointAt(s);
      const Vec2 tangent = track.TangentAt(s);
      cv::Mat image;
      renderer.Render({at.x(), at.y(), std::atan2(tangent.y(), tangent.x())}, image);
      frames.push_back(std::move(image));
    }
  }
  return frames;
}

}  // namespace haptel::testing
