#include "haptel/view/renderer.hpp"

#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "haptel/view/view.hpp"
#include "layers/ghost_layer.hpp"
#include "layers/gl_kit.hpp"
#include "layers/map_layer.hpp"
#include "layers/overlay_layer.hpp"
#include "layers/screen_layer.hpp"
#include "layers/third_person_layer.hpp"
#include "layers/tiles_layer.hpp"
#include "layers/world_layer.hpp"

namespace haptel::view {
namespace {

constexpr float kFovYDeg = 60.0f;
constexpr float kNear = 0.05f;
constexpr float kFar = 20.0f;

}  // namespace

/// What the Renderer draws with: the camera, the screen the layers share,
/// the textured-quad program, and the layers in drawing order.
struct Renderer::State {
  Eigen::Matrix4f projection;
  Eigen::Matrix4f view_projection;  ///< as last drawn (the view turns with a tracked gaze)
  bool gaze_tracked = false;        ///< in the last drawn model
  layers::VideoScreen screen;
  layers::TexturedQuads quads;
  std::vector<std::unique_ptr<layers::Layer>> layers;
  const layers::MapLayer* map = nullptr;  ///< for MapPoint

  /// The layers as one eye sees them, into a `width`×`height` viewport from
  /// column `x0`.
  void DrawEye(const ViewModel& model, double t_s, const Eigen::Matrix4f& eye_view_projection,
               int x0, int width, int height) {
    glViewport(x0, 0, width, height);
    glEnable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    const layers::Frame frame{width, height, eye_view_projection, t_s};
    for (const auto& layer : layers) layer->Draw(model, frame);
    glDisable(GL_BLEND);
    glBindVertexArray(0);
  }
};

namespace {

/// The view's layers, back to front: the one place that lists them. A
/// feature that draws adds its layer here (and its files to
/// view/CMakeLists.txt); nothing else changes.
std::vector<std::unique_ptr<layers::Layer>> MakeLayers(int width, int height,
                                                       layers::VideoScreen& screen,
                                                       const layers::TexturedQuads& quads,
                                                       const layers::MapLayer*& map) {
  std::vector<std::unique_ptr<layers::Layer>> list;
  list.push_back(std::make_unique<layers::WorldLayer>(screen));
  list.push_back(std::make_unique<layers::ScreenLayer>(screen, quads));
  list.push_back(std::make_unique<layers::GhostLayer>(screen, quads));
  list.push_back(std::make_unique<layers::OverlayLayer>(width, height, quads));
  list.push_back(std::make_unique<layers::ThirdPersonLayer>(width, height, quads));
  list.push_back(std::make_unique<layers::TilesLayer>(quads));
  auto map_layer = std::make_unique<layers::MapLayer>(quads);
  map = map_layer.get();
  list.push_back(std::move(map_layer));
  return list;
}

/// Throws ViewError when the current context is below GL 3.3.
void RequireGl33() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33) {
    throw ViewError("view: OpenGL 3.3 core is needed, this context has " + std::to_string(major) +
                    "." + std::to_string(minor));
  }
}

}  // namespace

Renderer::Renderer(int width, int height, const ScreenPlacement& screen,
                   const StereoOptions& stereo)
    : width_(width), height_(height), stereo_(stereo) {
  RequireGl33();
  state_ = std::make_unique<State>();
  State& s = *state_;
  s.screen.placement = screen;
  // In stereo every layer draws into one eye's half, as into a frame of its own.
  s.layers = MakeLayers(eye_width(), height, s.screen, s.quads, s.map);
  s.projection = layers::Perspective(
      kFovYDeg, static_cast<float>(eye_width()) / static_cast<float>(height), kNear, kFar);
  s.view_projection =
      s.projection * layers::LookAt(layers::kEye, layers::kTarget, Eigen::Vector3f::UnitZ());
  glViewport(0, 0, width, height);
}

Renderer::~Renderer() = default;

std::array<std::array<double, 3>, 4> Renderer::ScreenCorners() const {
  const layers::VideoScreen& screen = state_->screen;
  const auto& c = screen.placement.centre;
  const double hw = screen.placement.width / 2.0;
  const double hh = hw * screen.aspect;
  std::array<std::array<double, 3>, 4> corners{{{c[0], c[1] + hw, c[2] + hh},
                                                {c[0], c[1] - hw, c[2] + hh},
                                                {c[0], c[1] - hw, c[2] - hh},
                                                {c[0], c[1] + hw, c[2] - hh}}};
  if (state_->gaze_tracked) {
    for (auto& corner : corners) corner = screen.AboutEyeOf(corner);
  }
  return corners;
}

double Renderer::focal_px() const {
  return height_ / 2.0 / std::tan(kFovYDeg / 2.0 * std::numbers::pi / 180.0);
}

bool Renderer::Project(const std::array<double, 3>& point, double& px, double& py) const {
  const Eigen::Vector4f clip =
      state_->view_projection * Eigen::Vector4f(static_cast<float>(point[0]),
                                                static_cast<float>(point[1]),
                                                static_cast<float>(point[2]), 1.0f);
  if (clip.w() <= 0.0f) return false;
  const double ndc_x = clip.x() / clip.w();
  const double ndc_y = clip.y() / clip.w();
  px = (ndc_x + 1.0) / 2.0 * eye_width();
  py = (1.0 - ndc_y) / 2.0 * height_;
  return true;
}

void Renderer::Draw(const ViewModel& model, double t_s) {
  State& s = *state_;
  // A tracked gaze turns the view with the head and the screen with the camera.
  const Gaze& gaze = model.gaze;
  // A tracked head looks level when it looks ahead (a pilot's eyes, not a
  // desk's): the screen should hang at the eye's height in front of it.
  const Eigen::Vector3f target =
      gaze.tracked ? Eigen::Vector3f(layers::kEye + layers::Turn(gaze.look_pan, gaze.look_tilt) *
                                                        Eigen::Vector3f::UnitX())
                   : layers::kTarget;
  if (gaze.tracked || s.gaze_tracked) {
    s.view_projection =
        s.projection * layers::LookAt(layers::kEye, target, Eigen::Vector3f::UnitZ());
  }
  s.gaze_tracked = gaze.tracked;
  s.screen.turn = gaze.tracked ? layers::Turn(gaze.screen_pan, gaze.screen_tilt)
                               : Eigen::Quaternionf::Identity();
  glViewport(0, 0, width_, height_);
  glClearColor(0.55f, 0.62f, 0.70f, 1.0f);  // a light room
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glDisable(GL_CULL_FACE);  // few triangles: both sides cost nothing, and no winding to get wrong
  if (!stereo_.on) {
    s.DrawEye(model, t_s, s.view_projection, 0, width_, height_);
    return;
  }
  // Each eye half the distance apart to its side of the head's centre,
  // looking parallel to it (no toe-in: a far point lands alike in both).
  const Eigen::Vector3f forward = target - layers::kEye;
  const Eigen::Vector3f left = Eigen::Vector3f::UnitZ().cross(forward).normalized();
  for (int eye = 0; eye < 2; ++eye) {
    const Eigen::Vector3f shift =
        left * static_cast<float>((eye == 0 ? 0.5 : -0.5) * stereo_.ipd_m);
    const Eigen::Matrix4f eye_view_projection =
        s.projection *
        layers::LookAt(layers::kEye + shift, target + shift, Eigen::Vector3f::UnitZ());
    glClear(GL_DEPTH_BUFFER_BIT);  // the second eye's depth is its own
    s.DrawEye(model, t_s, eye_view_projection, eye * eye_width(), eye_width(), height_);
  }
}

bool Renderer::MapPoint(double x, double y, double& px, double& py) const {
  return state_->map->MapPoint(x, y, px, py);
}

void Renderer::ReadPixelsRaw(cv::Mat& rgba) const {
  rgba.create(height_, width_, CV_8UC4);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
}

void Renderer::ReadPixels(cv::Mat& bgr) const {
  cv::Mat rgba;
  ReadPixelsRaw(rgba);
  cv::Mat flipped;
  cv::flip(rgba, flipped, 0);
  cv::cvtColor(flipped, bgr, cv::COLOR_RGBA2BGR);
}

}  // namespace haptel::view
