#pragma once
/// @file A picture of one run: the track from above, to scale, with the gates
/// as the run took them, the driven path coloured by speed, the contacts, and
/// a title saying what the run was and how it ended.
///
/// World frame: x right, y up (the image's rows are flipped). The map fits the
/// track and the path with a margin; the picture is kLongSide pixels on its
/// long side. Colours (BGR): a passed gate green, a missed one (crossed
/// outside its posts) red, one never reached grey; the path by speed on the
/// "plasma" colour map (dark blue at 0 m/s to yellow at the run's top speed,
/// with no green or red in it, so gates and contacts read unambiguously);
/// contacts as red crosses outlined in black.
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/track.hpp"
#include "haptel/record/recorder.hpp"

namespace haptel::record {

/// The picture and where things are in it.
struct RunPicture {
  static constexpr int kLongSide = 1000;  ///< px

  cv::Mat image;               ///< 8-bit BGR, kLongSide on its long side
  double px_per_m = 0.0;       ///< the map's scale
  double min_x = 0.0;          ///< world x at pixel column origin_px.x
  double max_y = 0.0;          ///< world y at pixel row origin_px.y
  cv::Point2d origin_px;       ///< pixel of (min_x, max_y): the map's top left
  cv::Rect speed_legend;       ///< the colour bar: first column 0 m/s, last max_speed_mps
  double max_speed_mps = 0.0;  ///< the top of the legend: the run's top speed (1 if it never moved)

  /// The pixel (column, row) of a world point, sub-pixel.
  cv::Point2d ToPixel(double x, double y) const {
    return {origin_px.x + (x - min_x) * px_per_m, origin_px.y + (max_y - y) * px_per_m};
  }
};

/// Draws `run` on `track` (see the file comment). Speeds are magnitudes
/// (reversing counts as moving); non-finite path points and contacts are left out.
/// `also_show`: world points the map must take in besides the track and the
/// path (a blimp course's buildings and gates).
RunPicture RenderRunPicture(const RunRecord& run, const TrackConfig& track,
                            const std::vector<Vec2>& also_show = {});

/// The picture of a blimp's flight: the course from above (buildings
/// outlined, each gate a bar across its opening coloured as the run took it,
/// the landing circle, the start), the flown path coloured by speed, the
/// contacts, and the title, on RenderRunPicture's map and legend.
RunPicture RenderBlimpRunPicture(const RunRecord& run, const BlimpCourseConfig& course);

/// Writes `picture` as PNG to `png` (written beside and renamed over, so a
/// reader never sees half of it), creating its folder. Throws
/// std::runtime_error naming `png` if the folder or the file cannot be written.
void WriteRunPicture(const RunPicture& picture, const std::filesystem::path& png);

/// Renders the run and writes it as PNG to `png`, creating its folder.
/// Throws std::runtime_error naming `png` if the folder or the file cannot be
/// written.
void DrawRunPicture(const RunRecord& run, const TrackConfig& track,
                    const std::filesystem::path& png);

/// Where a run's picture goes: <the database's folder>/pictures/<the
/// database's stem>-run-<id>.png (runs.db's run 7: pictures/runs-run-7.png),
/// so that two databases in one folder never share a picture's name.
std::filesystem::path RunPicturePath(const std::filesystem::path& database, int64_t run_id);

}  // namespace haptel::record
