#pragma once
/// @file The short test track (config/tracks/test-short.yaml) with one
/// obstacle on its centre line just past the start, so that a vehicle driven
/// straight ahead meets a contact within a few seconds: the mouse device's
/// wall and shake, in its tests and `haptel bench hands`.
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace haptel::testing {

/// Writes `dir`/obstacle-ahead.yaml from `short_track` (the shipped
/// test-short.yaml) and returns its path. The obstacle: 5 cm round at
/// (0.05, 0), 0.35 m ahead of the start, off the first gate's line.
inline std::filesystem::path WriteObstacleAheadTrack(const std::filesystem::path& short_track,
                                                     const std::filesystem::path& dir) {
  std::ifstream in(short_track);
  if (!in) throw std::runtime_error("cannot read " + short_track.string());
  std::stringstream text;
  text << in.rdbuf();
  const auto file = dir / "obstacle-ahead.yaml";
  std::ofstream out(file);
  out << text.str() << "\n# an obstacle ahead of the start (testing/obstacle_track.hpp)\n"
      << "obstacles:\n  - {center: [0.05, 0.0], radius: 0.05}\n";
  if (!out) throw std::runtime_error("cannot write " + file.string());
  return file;
}

}  // namespace haptel::testing
