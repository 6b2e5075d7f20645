#pragma once
/// @file What the operator's view draws in one frame, as flat data: shapes in
/// the device frame (x forward, y left, z up; metres), the vehicle's latest
/// video image for the virtual screen, the overlay (lap clock, gates,
/// contacts, HUD) and, with the predictive display, the ghost and the map.
/// Filled by a ViewSource on the view thread each frame.
#include <array>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "haptel/video/frame.hpp"

namespace haptel::view {

struct Rgba {
  float r = 1, g = 1, b = 1, a = 1;
};

enum class ShapeKind : uint8_t {
  kBox,       ///< size = half extents (x, y, z)
  kSphere,    ///< size[0] = radius
  kCapsule,   ///< size[0] = radius, size[1] = half length of the cylinder part; axis = local x
  kCylinder,  ///< size[0] = radius, size[1] = half length; axis = local x
};

struct Shape {
  ShapeKind kind = ShapeKind::kBox;
  std::array<double, 3> position{};
  std::array<double, 4> orientation{1, 0, 0, 0};  ///< (w, x, y, z)
  std::array<double, 3> size{};
  Rgba color;
};

/// Text and indicators drawn over the world.
struct Overlay {
  char interface_name[32] = "";
  char operator_name[16] = "";
  double t_s = 0.0;  ///< run clock
  /// Lap clock. Negative: no lap (a camera station's view): no lap, gates
  /// or contact lines are drawn.
  double lap_time_s = 0.0;
  double time_left_s = -1;  ///< until the time limit (negative: none)
  int gates_passed = 0;
  int gates_total = 0;
  int obstacles_touched = 0;
  char last_contact[40] = "";  ///< e.g. "left bumper at 12.3 s" (empty: none yet)
  bool contact_now = false;    ///< a bumper is pressed now
  /// HUD (the HUD interfaces; the gesture interface may show it too).
  bool hud = false;
  double speed_mps = 0.0;
  double speed_max_mps = 1.0;  ///< the speedometer's full scale
  bool turn_left = false;      ///< indicator: on while turning left (drawn flashing)
  bool turn_right = false;
  bool throttle_locked = false;
  char message[96] = "";  ///< one line for the person (e.g. "grasp the wheel")
  char status[64] = "";   ///< the vehicle's own line (the blimp: height, power); empty: none
  /// The interface in use has controls in the world (a cockpit's wheel and
  /// lever): drawn only then, not after a switch to one without.
  bool controls_shown = false;
  /// Haptic shared control (gesture-shared): what pushes the hand, drawn as
  /// an arrow on a dial of the hand's horizontal plane (forward up, left
  /// left), as long as the push is strong.
  bool guidance_shown = false;      ///< the interface has shared control
  double guidance_forward_n = 0.0;  ///< N along the device's x (forward)
  double guidance_left_n = 0.0;     ///< N along its y (left)
  double guidance_max_n = 1.0;      ///< the push's bound: the dial's full length
  double guidance_ttc_s =
      -1.0;  ///< time to collision of the hand's command (negative: none in sight)
};

/// A head-tracked view (the blimp's pilot camera, thesis 8.2.3): the view
/// turns with the person's head, and the video screen hangs where the vehicle
/// camera actually points, so the picture stays where it looks. Angles turn
/// about the eye: pan positive left, tilt positive up, rad.
struct Gaze {
  bool tracked = false;   ///< false: the fixed view, the screen where it was placed
  double look_pan = 0.0;  ///< the person's head
  double look_tilt = 0.0;
  double screen_pan =
      0.0;  ///< the vehicle camera's direction as applied (lags the head by the link)
  double screen_tilt = 0.0;
};

/// A point in the camera's picture as fractions of its width and height from
/// its top-left corner: drawn on whatever size the decoded picture has.
struct PicturePoint {
  float u = 0.0f;
  float v = 0.0f;
};

/// A line on the floor as seen in the picture.
struct PictureSegment {
  PicturePoint a;
  PicturePoint b;
};

/// A pose on the track's map (track frame: x east, y north; m, rad).
struct MapPose {
  float x = 0.0f;
  float y = 0.0f;
  float heading = 0.0f;
  float z = 0.0f;  ///< height above the ground, m (the blimp's; 0 on the ground)
};

/// The predictive display (haptel run --predict on): where the vehicle is
/// now by its model, and where the command being given takes it over the
/// next second, in the camera picture being shown and on the track's map.
/// Flat and fixed-size (published through a seqlock); `shown` false draws
/// nothing.
struct Prediction {
  static constexpr int kOutlineMax = 64;
  static constexpr int kPathMax = 48;
  bool shown = false;
  /// In the picture: the ghost's silhouette, a convex polygon (empty when it
  /// is out of the camera's sight), and its path ahead on the floor, each
  /// clipped to what lies in front of the camera.
  int outline_count = 0;
  std::array<PicturePoint, kOutlineMax> outline{};
  int path_count = 0;
  std::array<PictureSegment, kPathMax> path{};
  /// On the map: the vehicle as last reported, as predicted now, the path
  /// ahead (its first point is the predicted pose), and its body's radius.
  MapPose reported;
  MapPose predicted;
  int map_path_count = 0;
  std::array<MapPose, kPathMax> map_path{};
  float body_radius = 0.1f;
  float one_way_delay_s = 0.0f;  ///< how far ahead of its video the ghost is
  /// The map says the heights (z) of the reported pose, the ghost and the
  /// path's end: a flying vehicle (the blimp), whose picture has no ghost.
  bool heights = false;
};

/// The track as the predictive display's map draws it, to scale (track
/// frame, m). Built once per run.
struct TrackMap {
  struct Line {
    double ax = 0, ay = 0, bx = 0, by = 0;
  };
  /// kLanding: the blimp's landing circle (drawn as a ring).
  enum class PostKind : uint8_t { kLeft, kRight, kObstacle, kLanding };
  struct Post {
    double x = 0, y = 0, radius = 0;
    PostKind kind = PostKind::kObstacle;
  };
  std::vector<Line> walls;
  std::vector<Line> gates;  ///< from post to post
  Line start;               ///< the start and finish line
  std::vector<Post> posts;  ///< gate posts and round obstacles
  /// Text at a place: a blimp gate's opening ("1.0-3.0 m" above ground).
  struct Label {
    double x = 0, y = 0;
    std::string text;
  };
  std::vector<Label> labels;
};

/// A fleet's vehicle as its tile shows it (haptel run --fleet): who
/// commands it now.
enum class TileState : uint8_t {
  kDriven,  ///< the operator drives it: its video is on the big screen
  kHeld,    ///< held safe while another is driven (stopped, at neutral)
  kDone,    ///< its course is over (completed, crashed, capped); held safe
  kLost,    ///< it stopped answering
};

/// The fleet's tiles: every vehicle's name, state and lap, one tile each,
/// with the driven one highlighted, and a line on the HUD saying who is
/// driven and how to switch. Flat and fixed-size (published through a
/// seqlock); the tiles' video images travel apart (ViewModel::tile_video).
struct Tiles {
  static constexpr int kMax = 9;  ///< the keys 1..9
  struct Tile {
    char name[24] = "";
    TileState state = TileState::kHeld;
    double lap_time_s = 0.0;  ///< the lap clock (0 before the start)
    int gates_passed = 0;
    int gates_total = 0;
  };
  int count = 0;  ///< 0: no tiles (a single vehicle's view)
  std::array<Tile, kMax> tile{};
  /// The HUD line: the driven vehicle, the last switch and the keys.
  char line[96] = "";
};

/// A tile's text under its picture, e.g. "robot-b DRIVEN lap 4.2 s 1/2":
/// what the person reads (the renderer draws exactly this).
std::string TileText(const Tiles::Tile& tile);

struct ViewModel {
  /// Everything in the world: proxy or tracked hands, controls, scene bodies,
  /// the gesture wall. Reserved once; Fill clears and refills it.
  std::vector<Shape> shapes;
  video::Frame video;  ///< the vehicle's latest picture, for the screen
  Overlay overlay;
  Gaze gaze;
  Prediction prediction;
  /// The map the prediction is drawn on (null: no map).
  std::shared_ptr<const TrackMap> map;
  /// A fleet's tiles and each tile's latest picture (same order).
  Tiles tiles;
  std::array<video::Frame, Tiles::kMax> tile_video;
  /// The third-person view (a practice lap; haptel run --third-person): a
  /// chase camera's picture of the robot on its track, drawn as an inset
  /// labelled kThirdPersonLabel (renderer.hpp). No image: no inset.
  video::Frame third_person;
};

}  // namespace haptel::view
