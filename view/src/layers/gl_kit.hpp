#pragma once
/// @file What the layers share to draw with OpenGL 3.3 core: shader programs,
/// indexed meshes, textures, the textured-quad program every picture and
/// panel is drawn with, the camera's matrices, and OpenCV's sub-pixel
/// drawing for the bitmaps rasterised on the CPU. Written once here, never
/// copied into a layer.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace haptel::view::layers {

/// Compiles and links a program; throws ViewError with GL's log when it
/// does not compile or link.
GLuint LinkProgram(const char* vertex_source, const char* fragment_source);

/// Indexed triangles with position and normal (lit) or position and uv
/// (textured). Indexed, so a software rasteriser shades each shared vertex
/// once (llvmpipe's vertex cache), not once per triangle.
struct Mesh {
  GLuint vao = 0;
  GLuint vbo = 0;
  GLuint ebo = 0;
  GLsizei indices = 0;
  std::vector<float> unique;    ///< 6 floats per distinct vertex (kept for batching)
  std::vector<uint32_t> index;  ///< triangles into `unique`

  /// `data` holds 6 floats per vertex of a triangle list: xyz then normal or
  /// (u, v, 0). Identical vertices are merged.
  void Upload(const std::vector<float>& data, bool textured);
  void Release();
  void Draw() const;
};

/// A texture sampled linearly and clamped at its edges, without storage yet.
GLuint MakeTexture();

/// Uploads a BGR picture whole into the bound texture: new storage when its
/// size differs from `cols`×`rows` (then updated), else in place.
void UploadBgr(const cv::Mat& bgr, int& cols, int& rows);
/// Uploads a BGRA bitmap whole into the bound texture, as new storage.
void UploadBgra(const cv::Mat& bgra);

/// The textured-quad program and its two quads, shared by every layer that
/// draws a picture or a panel: the screen's quad in the world, and the
/// full-view quad placed on a rectangle of pixels.
class TexturedQuads {
 public:
  TexturedQuads();
  ~TexturedQuads();
  TexturedQuads(const TexturedQuads&) = delete;
  TexturedQuads& operator=(const TexturedQuads&) = delete;

  /// Binds the program for pictures in the world: tested against depth (a
  /// hand in front of the screen hides it), blended by alpha.
  void BeginInWorld() const;
  /// Binds the program for panels over the world, in pixels: no depth test,
  /// blended by alpha.
  void BeginOverWorld() const;

  /// The unit quad of x = 0 facing −x (corners (y, z) ∈ [−1, 1]², v = 0 at
  /// the top, u = 0 on the +y side) through `mvp`, textured by the bound
  /// texture's window `uv` (offset u, v, then width, height).
  void DrawScreenQuad(const Eigen::Matrix4f& mvp,
                      const std::array<float, 4>& uv = {0, 0, 1, 1}) const;
  /// The bound texture's window `uv` on the pixel rectangle `rect` (y down)
  /// of a `view_width`×`view_height` view.
  void DrawPixels(const cv::Rect& rect, int view_width, int view_height,
                  const std::array<float, 4>& uv = {0, 0, 1, 1}) const;

 private:
  GLuint program_ = 0;
  GLint mvp_ = -1, uv_rect_ = -1;
  Mesh screen_, fullscreen_;
};

// --- The camera and the turns about the eye (device frame: x forward, y
// left, z up; metres). ---

/// The camera: behind and above the workspace, looking forward and down (a
/// tracked gaze looks level, turned by the head).
inline const Eigen::Vector3f kEye(-0.45f, 0.0f, 0.30f);
inline const Eigen::Vector3f kTarget(0.40f, 0.0f, 0.10f);

Eigen::Matrix4f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                       const Eigen::Vector3f& up);
Eigen::Matrix4f Perspective(float fovy_deg, float aspect, float near, float far);
/// A turn about the eye: pan about +z (positive left), then tilt (positive
/// up, i.e. about -y in the device frame).
Eigen::Quaternionf Turn(double pan, double tilt);
/// `point` turned about the eye by `turn`.
std::array<double, 3> AboutEye(const Eigen::Quaternionf& turn, const std::array<double, 3>& point);
/// Translation, rotation (w, x, y, z; identity when degenerate), then scale.
Eigen::Matrix4f Model(const std::array<double, 3>& position, const std::array<double, 4>& q_wxyz,
                      const Eigen::Vector3f& scale);

// --- Bitmaps drawn on the CPU with OpenCV (BGRA). ---

inline cv::Scalar Bgra(double b, double g, double r, double a = 255) {
  return cv::Scalar(b, g, r, a);
}
constexpr int kShift = 4;  ///< sub-pixel bits for OpenCV's drawing
constexpr double kOne = 1 << kShift;
/// (x, y) in pixels as OpenCV's sub-pixel point (kShift bits).
cv::Point Fixed(double x, double y);

/// The predictive display's colours (BGRA), shared by the ghost and the map:
/// the ghost and its path in magenta, which nothing in the synthetic
/// camera's world is (sky blue, brown floor, pale walls, red and green
/// posts, orange obstacles); the vehicle as last reported in white.
inline const cv::Scalar kGhostLine(255, 0, 255, 255);
inline const cv::Scalar kGhostFill(255, 0, 255, 110);  // see-through: the floor shows
inline const cv::Scalar kReported(255, 255, 255, 255);

}  // namespace haptel::view::layers
