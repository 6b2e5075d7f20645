#pragma once
/// @file Draws a ViewModel with OpenGL 3.3 core: the shapes lit from above,
/// the vehicle's video on a virtual screen in front of the operator (thesis
/// fig. 8.4), and the overlay (lap clock, gates, contacts, HUD) on top.
///
/// The camera sits behind and above the device workspace looking forward and
/// down, so the hands, the wheel and the lever are in the lower half and the
/// screen fills the upper half. With a tracked gaze (the blimp) the camera
/// looks level and turns with the head, and the screen turns about the eye
/// with the vehicle camera. Everything is in the device frame (x forward,
/// y left, z up; metres). A Renderer needs a current GL 3.3 context on the
/// calling thread for its whole life; it allocates its GL objects once.
/// It draws a list of layers, back to front, each in its own file under
/// view/src/layers/ (the world, the screen, the ghost, the overlay, the
/// third-person inset, the fleet's tiles, the map).
#include <array>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "haptel/view/view_model.hpp"

namespace haptel::view {

/// Where the virtual screen hangs (device frame): its centre and width; the
/// height follows the video's aspect ratio (4:3 until the first frame).
struct ScreenPlacement {
  std::array<double, 3> centre{0.70, 0.0, 0.25};
  double width = 0.80;
};

/// Side-by-side stereo for a head-mounted display: the world drawn twice,
/// from two eyes `ipd_m` apart (each turned with the head, looking
/// parallel), the left eye's picture in the frame's left half and the
/// right's in the right half, each half with its own overlay.
struct StereoOptions {
  bool on = false;
  double ipd_m = 0.064;  ///< the interpupillary distance, m
};

/// The screen close before the eye, filling the picture: the camera's view
/// with nothing in front of it (no hands to show).
inline ScreenPlacement DirectViewScreen() { return {{0.35, 0.0, 0.10}, 1.05}; }

/// For a tracked gaze (Gaze::tracked): the screen a metre straight ahead at
/// the eye's height, square to the level look; the hands show below it.
inline ScreenPlacement HeadTrackedScreen() { return {{0.55, 0.0, 0.30}, 0.90}; }

/// The text lines the overlay shows for `overlay`, top to bottom: what the
/// person reads (the renderer draws exactly these, so tests read them here).
std::vector<std::string> OverlayLines(const Overlay& overlay);
/// The HUD's speedometer text ("0.42 m/s"), empty without a HUD.
std::string HudSpeedText(const Overlay& overlay);
/// Where a fleet's tile `index` of `count` is drawn in a `width`×`height`
/// view, pixels from the top-left corner: a column down the right edge, the
/// picture over two lines of text (TileLabelFor). The driven one has a
/// yellow frame (kTileFrameBgr) around it, the others none.
struct TileBox {
  int x = 0, y = 0, width = 0, height = 0;
};
TileBox TileRect(int index, int count, int width, int height);
/// A tile's text as drawn under its picture (TileText's words): the name and
/// state, then the lap and gates, each line at the largest scale up to the
/// view's own (0.40 at 576 px high) at which it fits the tile's width, so
/// nothing is cut off whatever the name or the number of tiles.
struct TileLabel {
  std::array<std::string, 2> lines;
  double scale = 0.0;   ///< cv::FONT_HERSHEY_SIMPLEX's font scale
  int line_height = 0;  ///< px from one baseline to the next
  int margin = 4;       ///< px left clear inside the tile on either side
};
TileLabel TileLabelFor(const Tiles::Tile& tile, int tile_width, int view_height);
/// The driven tile's frame, BGR: nothing else in the view is this yellow.
inline constexpr std::array<int, 3> kTileFrameBgr{0, 220, 255};

/// Where the third-person view's picture (ViewModel::third_person) is
/// drawn in a `width`×`height` view, pixels from the top-left corner: on the
/// left, under the overlay's text panel, 4:3, with its label on a line just
/// above it (ThirdPersonLabelRect). Clear of the map (top right), the HUD
/// (bottom right), shared control's dial (bottom left) and the message line.
TileBox ThirdPersonRect(int width, int height);
/// The label's line above the picture.
TileBox ThirdPersonLabelRect(int width, int height);
/// What the label says, so nobody takes the picture for the robot's camera.
inline constexpr const char* kThirdPersonLabel = "third-person (practice)";

/// Whether a turn indicator that is on is lit at time `t_s` (they flash at
/// 1.5 Hz, lit for the first half of each period, as a car's do).
bool IndicatorLit(double t_s);

/// Where shared control's dial and arrow go on a `width`×`height` overlay
/// (pixels, y down): the dial's centre and radius, and the arrow's tip (at
/// the centre when nothing pushes). Forward is up the screen, left is left.
struct GuidanceDial {
  int centre_x = 0, centre_y = 0, radius = 0;
  int tip_x = 0, tip_y = 0;
};
GuidanceDial GuidanceDialOf(const Overlay& overlay, int width, int height);

class Renderer {
 public:
  /// Compiles the shaders and builds the meshes and textures for a
  /// `width`×`height` framebuffer. Throws ViewError when GL is below 3.3 or a
  /// shader does not compile (with GL's log).
  Renderer(int width, int height, const ScreenPlacement& screen = {},
           const StereoOptions& stereo = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Draws one frame into the current framebuffer; `t_s` drives the
  /// indicators' flashing. Uploads the video image only when its id changes.
  void Draw(const ViewModel& model, double t_s);

  /// The framebuffer as drawn (after Draw, before the swap), BGR, top row
  /// first, into `bgr` (reallocated only when its size differs).
  void ReadPixels(cv::Mat& bgr) const;
  /// The framebuffer as drawn, RGBA bottom row first (GL's order), straight
  /// into `rgba` (CV_8UC4, height×width): the recorder converts it later.
  void ReadPixelsRaw(cv::Mat& rgba) const;

  /// Where a device-frame point lands in the image as last drawn (the view
  /// turns with a tracked gaze): pixels from the top-left corner. False when
  /// the point is behind the camera. In stereo: as the cyclopean eye between
  /// the two would see it, in a half's pixels.
  bool Project(const std::array<double, 3>& point, double& px, double& py) const;
  /// The screen's corners now (top-left, top-right, bottom-right,
  /// bottom-left as the operator sees them), device frame: turned about the
  /// eye by the last drawn model's gaze when it is tracked.
  std::array<std::array<double, 3>, 4> ScreenCorners() const;
  /// Where a track point (m) lands on the prediction's map as last drawn:
  /// pixels from the top-left corner. False when the last frame drew no map.
  bool MapPoint(double x, double y, double& px, double& py) const;

  int width() const { return width_; }
  int height() const { return height_; }
  /// The width one eye's picture has: the frame's, or half of it in stereo.
  int eye_width() const { return stereo_.on ? width_ / 2 : width_; }
  /// The eyes' focal length in pixels (both axes: square pixels), so that a
  /// point d metres ahead and x to the side lands f·x/d from the centre.
  double focal_px() const;

 private:
  /// The camera, the screen and the layers (view/src/layers/).
  struct State;
  int width_;
  int height_;
  StereoOptions stereo_;
  std::unique_ptr<State> state_;
};

}  // namespace haptel::view
