#include "haptel/view/renderer.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <opencv2/imgproc.hpp>

#include "haptel/view/view.hpp"

namespace haptel::view {
namespace {

// The camera: behind and above the workspace, looking forward and down (a
// tracked gaze looks level, turned by the head).
const Eigen::Vector3f kEye(-0.45f, 0.0f, 0.30f);
const Eigen::Vector3f kTarget(0.40f, 0.0f, 0.10f);
constexpr float kFovYDeg = 60.0f;
constexpr float kNear = 0.05f;
constexpr float kFar = 20.0f;
const Eigen::Vector3f kLightDir =
    Eigen::Vector3f(0.3f, -0.2f, -1.0f).normalized();  // pointing down
constexpr double kIndicatorHz = 1.5;

// Lit shapes arrive already in the world frame (the CPU transforms them into
// one batch): a software rasteriser's cost per draw call dwarfs its cost per
// vertex, so the whole world is one draw.
const char* kLitVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec4 vertex_color;
uniform mat4 mvp;
out vec3 world_normal;
out vec4 color;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  world_normal = normal;
  color = vertex_color;
})";

const char* kLitFragment = R"(#version 330 core
in vec3 world_normal;
in vec4 color;
uniform vec3 light_dir;
out vec4 frag;
void main() {
  float lambert = max(dot(normalize(world_normal), -light_dir), 0.0);
  frag = vec4(color.rgb * (0.35 + 0.65 * lambert), color.a);
})";

const char* kTexVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
uniform mat4 mvp;
uniform vec4 uv_rect;  // offset (xy) and scale (zw) of the texture window
out vec2 tex_uv;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  tex_uv = uv_rect.xy + uv * uv_rect.zw;
})";

const char* kTexFragment = R"(#version 330 core
in vec2 tex_uv;
uniform sampler2D image;
out vec4 frag;
void main() { frag = texture(image, tex_uv); })";

GLuint Compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == 0) {
    char log[1024] = "";
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw ViewError(std::string("view: shader does not compile: ") + log);
  }
  return shader;
}

GLuint Link(const char* vertex, const char* fragment) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, fragment);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok == 0) {
    char log[1024] = "";
    glGetProgramInfoLog(program, sizeof log, nullptr, log);
    glDeleteProgram(program);
    throw ViewError(std::string("view: shader program does not link: ") + log);
  }
  return program;
}

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
  void Upload(const std::vector<float>& data, bool textured) {
    std::map<std::array<float, 6>, uint32_t> seen;
    unique.clear();
    index.clear();
    for (size_t i = 0; i + 6 <= data.size(); i += 6) {
      std::array<float, 6> v{};
      std::copy(data.begin() + static_cast<std::ptrdiff_t>(i),
                data.begin() + static_cast<std::ptrdiff_t>(i + 6), v.begin());
      auto [it, added] = seen.try_emplace(v, static_cast<uint32_t>(unique.size() / 6));
      if (added) unique.insert(unique.end(), v.begin(), v.end());
      index.push_back(it->second);
    }
    glGenVertexArrays(1, &vao);
    glGenBuffers(1, &vbo);
    glGenBuffers(1, &ebo);
    glBindVertexArray(vao);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(unique.size() * sizeof(float)),
                 unique.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(index.size() * sizeof(uint32_t)),
                 index.data(), GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), nullptr);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(1, textured ? 2 : 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                          reinterpret_cast<void*>(3 * sizeof(float)));
    glEnableVertexAttribArray(1);
    indices = static_cast<GLsizei>(index.size());
    glBindVertexArray(0);
  }
  void Release() {
    if (ebo != 0) glDeleteBuffers(1, &ebo);
    if (vbo != 0) glDeleteBuffers(1, &vbo);
    if (vao != 0) glDeleteVertexArrays(1, &vao);
    ebo = vbo = vao = 0;
  }
  void Draw() const {
    glBindVertexArray(vao);
    glDrawElements(GL_TRIANGLES, indices, GL_UNSIGNED_INT, nullptr);
  }
};

void Push(std::vector<float>& v, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  v.insert(v.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z()});
}

/// The unit cube (half extents 1).
std::vector<float> CubeMesh() {
  std::vector<float> v;
  for (int axis = 0; axis < 3; ++axis) {
    for (float sign : {-1.0f, 1.0f}) {
      Eigen::Vector3f n = Eigen::Vector3f::Zero();
      n[axis] = sign;
      const Eigen::Vector3f a = Eigen::Vector3f::Unit((axis + 1) % 3);
      const Eigen::Vector3f b = Eigen::Vector3f::Unit((axis + 2) % 3);
      const Eigen::Vector3f c[4] = {n - a - b, n + a - b, n + a + b, n - a + b};
      for (int i : {0, 1, 2, 0, 2, 3}) Push(v, c[i], n);
    }
  }
  return v;
}

/// The unit sphere.
std::vector<float> SphereMesh(int stacks = 6, int slices = 8) {
  std::vector<float> v;
  auto at = [&](int i, int j) {
    const double theta = M_PI * i / stacks;
    const double phi = 2 * M_PI * j / slices;
    return Eigen::Vector3f(static_cast<float>(std::sin(theta) * std::cos(phi)),
                           static_cast<float>(std::sin(theta) * std::sin(phi)),
                           static_cast<float>(std::cos(theta)));
  };
  for (int i = 0; i < stacks; ++i) {
    for (int j = 0; j < slices; ++j) {
      const Eigen::Vector3f p00 = at(i, j), p01 = at(i, j + 1), p10 = at(i + 1, j),
                            p11 = at(i + 1, j + 1);
      for (const Eigen::Vector3f& p : {p00, p10, p11, p00, p11, p01}) Push(v, p, p);
    }
  }
  return v;
}

/// The cylinder of radius 1 from x = −1 to x = 1, with caps.
std::vector<float> CylinderMesh(int slices = 8) {
  std::vector<float> v;
  auto ring = [&](int j) {
    const double phi = 2 * M_PI * j / slices;
    return Eigen::Vector3f(0.0f, static_cast<float>(std::cos(phi)),
                           static_cast<float>(std::sin(phi)));
  };
  const Eigen::Vector3f ex = Eigen::Vector3f::UnitX();
  for (int j = 0; j < slices; ++j) {
    const Eigen::Vector3f r0 = ring(j), r1 = ring(j + 1);
    for (const Eigen::Vector3f& p :
         {Eigen::Vector3f(r0 - ex), Eigen::Vector3f(r1 - ex), Eigen::Vector3f(r1 + ex),
          Eigen::Vector3f(r0 - ex), Eigen::Vector3f(r1 + ex), Eigen::Vector3f(r0 + ex)}) {
      Push(v, p, Eigen::Vector3f(0, p.y(), p.z()));
    }
    Push(v, ex, ex);
    Push(v, r0 + ex, ex);
    Push(v, r1 + ex, ex);
    Push(v, -ex, -ex);
    Push(v, r1 - ex, -ex);
    Push(v, r0 - ex, -ex);
  }
  return v;
}

/// The unit quad in x = 0 facing −x, corners (y, z) ∈ [−1, 1]², uv with v = 0
/// at the top and u = 0 on the left as seen from −x (which is +y).
std::vector<float> ScreenQuadMesh() {
  struct Corner {
    float y, z, u, v;
  };
  const Corner c[4] = {{1, 1, 0, 0}, {-1, 1, 1, 0}, {-1, -1, 1, 1}, {1, -1, 0, 1}};
  std::vector<float> v;
  for (int i : {0, 3, 2, 0, 2, 1}) v.insert(v.end(), {0.0f, c[i].y, c[i].z, c[i].u, c[i].v, 0.0f});
  return v;
}

/// A quad covering the viewport in clip space, v = 0 at the top.
std::vector<float> FullscreenQuadMesh() {
  const float c[4][4] = {{-1, 1, 0, 0}, {1, 1, 1, 0}, {1, -1, 1, 1}, {-1, -1, 0, 1}};
  std::vector<float> v;
  for (int i : {0, 3, 2, 0, 2, 1})
    v.insert(v.end(), {c[i][0], c[i][1], 0.0f, c[i][2], c[i][3], 0.0f});
  return v;
}

Eigen::Matrix4f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                       const Eigen::Vector3f& up) {
  const Eigen::Vector3f f = (target - eye).normalized();
  const Eigen::Vector3f s = f.cross(up).normalized();
  const Eigen::Vector3f u = s.cross(f);
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m.block<1, 3>(0, 0) = s.transpose();
  m.block<1, 3>(1, 0) = u.transpose();
  m.block<1, 3>(2, 0) = -f.transpose();
  m(0, 3) = -s.dot(eye);
  m(1, 3) = -u.dot(eye);
  m(2, 3) = f.dot(eye);
  return m;
}

Eigen::Matrix4f Perspective(float fovy_deg, float aspect, float near, float far) {
  const float f = 1.0f / std::tan(fovy_deg * static_cast<float>(M_PI) / 360.0f);
  Eigen::Matrix4f m = Eigen::Matrix4f::Zero();
  m(0, 0) = f / aspect;
  m(1, 1) = f;
  m(2, 2) = (far + near) / (near - far);
  m(2, 3) = 2.0f * far * near / (near - far);
  m(3, 2) = -1.0f;
  return m;
}

/// A turn about the eye: pan about +z (positive left), then tilt (positive
/// up, i.e. about -y in the device frame).
/// The transform that puts the full-screen quad (-1..1) on the pixel
/// rectangle x, y, width, height (y down) of a view_width x view_height view.
Eigen::Matrix4f PixelRect(int x, int y, int width, int height, int view_width, int view_height) {
  const float w = static_cast<float>(view_width), h = static_cast<float>(view_height);
  Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
  m(0, 0) = static_cast<float>(width) / w;
  m(1, 1) = static_cast<float>(height) / h;
  m(0, 3) = (2.0f * static_cast<float>(x) + static_cast<float>(width)) / w - 1.0f;
  m(1, 3) = 1.0f - (2.0f * static_cast<float>(y) + static_cast<float>(height)) / h;
  return m;
}

Eigen::Quaternionf Turn(double pan, double tilt) {
  return Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(pan), Eigen::Vector3f::UnitZ()) *
                            Eigen::AngleAxisf(static_cast<float>(-tilt), Eigen::Vector3f::UnitY()));
}

/// `point` turned about the eye by `turn`.
std::array<double, 3> AboutEye(const Eigen::Quaternionf& turn, const std::array<double, 3>& point) {
  const Eigen::Vector3f p =
      kEye + turn * (Eigen::Vector3f(static_cast<float>(point[0]), static_cast<float>(point[1]),
                                     static_cast<float>(point[2])) -
                     kEye);
  return {p.x(), p.y(), p.z()};
}

Eigen::Matrix4f Model(const std::array<double, 3>& position, const std::array<double, 4>& q_wxyz,
                      const Eigen::Vector3f& scale) {
  Eigen::Quaternionf q(static_cast<float>(q_wxyz[0]), static_cast<float>(q_wxyz[1]),
                       static_cast<float>(q_wxyz[2]), static_cast<float>(q_wxyz[3]));
  if (q.norm() < 1e-6f) q = Eigen::Quaternionf::Identity();
  Eigen::Affine3f a = Eigen::Affine3f::Identity();
  a.translate(Eigen::Vector3f(static_cast<float>(position[0]), static_cast<float>(position[1]),
                              static_cast<float>(position[2])));
  a.rotate(q.normalized());
  a.scale(scale);
  return a.matrix();
}

cv::Scalar Bgra(double b, double g, double r, double a = 255) { return cv::Scalar(b, g, r, a); }

// The predictive display's colours (BGRA): the ghost and its path in
// magenta, which nothing in the synthetic camera's world is (sky blue,
// brown floor, pale walls, red and green posts, orange obstacles); the
// vehicle as last reported in white.
const cv::Scalar kGhostLine(255, 0, 255, 255);
const cv::Scalar kGhostFill(255, 0, 255, 110);  // see-through: the floor shows
const cv::Scalar kReported(255, 255, 255, 255);
constexpr int kShift = 4;  // sub-pixel bits for OpenCV's drawing
constexpr double kOne = 1 << kShift;

cv::Point Fixed(double x, double y) {
  const auto fix = [](double c) {
    return static_cast<int>(std::lround(std::clamp(c, -1e5, 1e5) * kOne));
  };
  return {fix(x), fix(y)};
}

/// Draws the prediction's ghost and path into `ghost` (BGRA, the picture's
/// size; transparent where nothing is). Returns the rectangle it drew in
/// (empty: nothing in sight).
cv::Rect DrawGhost(cv::Mat& ghost, const Prediction& p) {
  const double w = ghost.cols, h = ghost.rows;
  const int thickness = std::max(3, ghost.cols / 160);  // 4 px in a 640-pixel picture
  double x0 = w, y0 = h, x1 = 0, y1 = 0;
  const auto at = [&](const PicturePoint& q) {
    const double x = q.u * w, y = q.v * h;
    x0 = std::min(x0, x);
    y0 = std::min(y0, y);
    x1 = std::max(x1, x);
    y1 = std::max(y1, y);
    return Fixed(x - 0.5, y - 0.5);  // OpenCV's coordinates are pixel centres
  };
  // The ghost's body see-through, the path over it (it runs on under the
  // ghost, on the floor the body hides), the ghost's outline last.
  const int n = std::clamp(p.outline_count, 0, Prediction::kOutlineMax);
  std::array<cv::Point, Prediction::kOutlineMax> pts;
  for (int i = 0; i < n; ++i) pts[static_cast<size_t>(i)] = at(p.outline[static_cast<size_t>(i)]);
  if (n >= 3) cv::fillConvexPoly(ghost, pts.data(), n, kGhostFill, cv::LINE_AA, kShift);
  for (int i = 0; i < std::clamp(p.path_count, 0, Prediction::kPathMax); ++i) {
    const cv::Point a = at(p.path[static_cast<size_t>(i)].a);
    const cv::Point b = at(p.path[static_cast<size_t>(i)].b);
    cv::line(ghost, a, b, kGhostLine, thickness, cv::LINE_AA, kShift);
  }
  if (n >= 3) {
    const cv::Point* poly = pts.data();
    cv::polylines(ghost, &poly, &n, 1, true, kGhostLine, thickness, cv::LINE_AA, kShift);
  }
  if (x1 < x0 || y1 < y0) return {};
  const int pad = thickness + 2;
  const cv::Rect drawn(
      cv::Point(static_cast<int>(std::floor(x0)) - pad, static_cast<int>(std::floor(y0)) - pad),
      cv::Point(static_cast<int>(std::ceil(x1)) + pad, static_cast<int>(std::ceil(y1)) + pad));
  return drawn & cv::Rect(0, 0, ghost.cols, ghost.rows);
}

/// The map's scale and offset for `map` in a `side`-pixel square: the
/// track's walls and posts fit, to scale, north up.
void FitMap(const TrackMap& map, int side, double& scale, double& ox, double& oy) {
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  const auto grow = [&](double x, double y, double r) {
    x0 = std::min(x0, x - r);
    y0 = std::min(y0, y - r);
    x1 = std::max(x1, x + r);
    y1 = std::max(y1, y + r);
  };
  for (const TrackMap::Line& l : map.walls) {
    grow(l.ax, l.ay, 0);
    grow(l.bx, l.by, 0);
  }
  for (const TrackMap::Post& p : map.posts) grow(p.x, p.y, p.radius);
  for (const TrackMap::Line& l : map.gates) {
    grow(l.ax, l.ay, 0);
    grow(l.bx, l.by, 0);
  }
  if (!map.walls.empty() || !map.posts.empty()) {  // a map with nothing but a start line is no map
    grow(map.start.ax, map.start.ay, 0);
    grow(map.start.bx, map.start.by, 0);
  }
  if (x1 < x0) {  // nothing to fit: a metre around the origin
    x0 = y0 = -0.5;
    x1 = y1 = 0.5;
  }
  const double margin = 0.06 * side;
  scale = (side - 2 * margin) / std::max({x1 - x0, y1 - y0, 1e-3});
  ox = side / 2.0 - scale * (x0 + x1) / 2;
  oy = side / 2.0 + scale * (y0 + y1) / 2;
}

}  // namespace

std::string TileText(const Tiles::Tile& tile) {
  const char* state = tile.state == TileState::kDriven ? "DRIVEN"
                      : tile.state == TileState::kHeld ? "held"
                      : tile.state == TileState::kDone ? "done"
                                                       : "LOST";
  char text[96];
  std::snprintf(text, sizeof text, "%s %s  lap %.1f s  %d/%d", tile.name, state, tile.lap_time_s,
                tile.gates_passed, tile.gates_total);
  return text;
}

TileBox TileRect(int index, int count, int width, int height) {
  // Up to four at 18% of the width; more shrink so the column still fits.
  const int gap = 6;
  const int line_h = static_cast<int>(20 * height / 576.0);
  int tile_w = static_cast<int>(0.18 * width);
  const int n = std::max(count, 1);
  const int room = height - 16 - (n - 1) * gap;
  if (n * (tile_w * 3 / 4 + line_h) > room) tile_w = (room / n - line_h) * 4 / 3;
  const int tile_h = tile_w * 3 / 4 + line_h;
  return {width - tile_w - 8, 8 + index * (tile_h + gap), tile_w, tile_h};
}

std::vector<std::string> OverlayLines(const Overlay& o) {
  std::vector<std::string> lines;
  char line[160];
  std::snprintf(line, sizeof line, "%s  (%s)", o.interface_name, o.operator_name);
  lines.emplace_back(line);
  if (o.time_left_s >= 0) {
    std::snprintf(line, sizeof line, "lap %.1f s   time left %.0f s", o.lap_time_s, o.time_left_s);
  } else {
    std::snprintf(line, sizeof line, "lap %.1f s", o.lap_time_s);
  }
  lines.emplace_back(line);
  std::snprintf(line, sizeof line, "gates %d/%d   obstacles %d", o.gates_passed, o.gates_total,
                o.obstacles_touched);
  lines.emplace_back(line);
  std::snprintf(line, sizeof line, "last contact: %s",
                o.last_contact[0] != '\0' ? o.last_contact : "none");
  lines.emplace_back(line);
  if (o.status[0] != '\0') lines.emplace_back(o.status);
  if (o.hud) {
    lines.push_back("speed " + HudSpeedText(o));
    if (o.throttle_locked) lines.emplace_back("THROTTLE LOCKED");
  }
  if (o.guidance_shown) {
    const double push = std::hypot(o.guidance_forward_n, o.guidance_left_n);
    if (o.guidance_ttc_s >= 0.0) {
      std::snprintf(line, sizeof line, "shared control: push %.1f N, obstacle in %.1f s", push,
                    o.guidance_ttc_s);
    } else {
      std::snprintf(line, sizeof line, "shared control: clear");
    }
    lines.emplace_back(line);
  }
  if (o.message[0] != '\0') lines.emplace_back(o.message);
  return lines;
}

TileBox ThirdPersonLabelRect(int width, int height) {
  const double k = height / 576.0;
  // Under the overlay's text panel (five lines at most), above the message
  // line at the bottom.
  const int top = static_cast<int>(158 * k);
  const int line_h = static_cast<int>(22 * k);
  const int room = height - top - line_h - static_cast<int>(60 * k);
  const int picture_w = std::max(4, std::min(static_cast<int>(0.30 * width), room * 4 / 3));
  return {8, top, picture_w, line_h};
}

TileBox ThirdPersonRect(int width, int height) {
  const TileBox label = ThirdPersonLabelRect(width, height);
  return {label.x, label.y + label.height, label.width, label.width * 3 / 4};
}

GuidanceDial GuidanceDialOf(const Overlay& o, int width, int height) {
  GuidanceDial d;
  d.radius = static_cast<int>(50 * height / 576.0);
  d.centre_x = d.radius + 24;
  d.centre_y = height - d.radius - 24;
  (void)width;  // the dial keeps to the left edge whatever the width
  const double push = std::hypot(o.guidance_forward_n, o.guidance_left_n);
  const double fraction = std::min(1.0, push / std::max(o.guidance_max_n, 1e-6));
  const double norm = std::max(push, 1e-12);
  // Forward (x) is up the screen, left (y) is left: a push back points down.
  d.tip_x =
      d.centre_x - static_cast<int>(std::lround(d.radius * fraction * o.guidance_left_n / norm));
  d.tip_y =
      d.centre_y - static_cast<int>(std::lround(d.radius * fraction * o.guidance_forward_n / norm));
  return d;
}

std::string HudSpeedText(const Overlay& o) {
  if (!o.hud) return {};
  char text[32];
  std::snprintf(text, sizeof text, "%.2f m/s", std::abs(o.speed_mps));
  return text;
}

bool IndicatorLit(double t_s) {
  const double phase = t_s * kIndicatorHz;
  return phase - std::floor(phase) < 0.5;
}

struct Renderer::Gl {
  GLuint lit = 0;
  GLint lit_mvp = -1, lit_light = -1;
  GLuint batch_vao = 0, batch_vbo = 0, batch_ebo = 0;
  std::vector<float> batch;  ///< position, normal, colour: 10 floats a vertex
  std::vector<uint32_t> batch_index;
  GLuint tex = 0;
  GLint tex_mvp = -1, tex_image = -1, tex_uv_rect = -1;
  Mesh cube, sphere, cylinder, screen, fullscreen;
  GLuint video_texture = 0;
  int video_cols = 0, video_rows = 0;
  uint64_t video_id = 0;
  bool have_video = false;
  GLuint overlay_texture = 0;
  cv::Mat overlay;  ///< BGRA, drawn on the CPU when its content changes
  std::string overlay_key;
  /// Where the overlay has anything: only these are blended (a software
  /// rasteriser pays for every blended pixel).
  std::vector<cv::Rect> overlay_rects;
  Eigen::Matrix4f projection;
  Eigen::Matrix4f view_projection;
  /// The predictive display's ghost, drawn on the CPU in the picture's own
  /// pixels each frame; only the rectangle holding it is cleared, uploaded
  /// and blended over the screen.
  GLuint ghost_texture = 0;
  cv::Mat ghost;  ///< BGRA, the video picture's size
  cv::Rect ghost_rect;
  /// The map: the track drawn once (map_base), the poses over it each frame.
  GLuint map_texture = 0;
  cv::Mat map_base, map;                         ///< BGRA, the panel's size
  const TrackMap* map_of = nullptr;              ///< the track map_base shows
  cv::Rect map_panel;                            ///< where the panel is, window pixels
  double map_scale = 0, map_ox = 0, map_oy = 0;  ///< track metres to panel pixels
  bool map_drawn = false;                        ///< in the last frame
  /// A fleet's tiles: the column drawn on the CPU when a tile's picture or
  /// text changes, uploaded whole (it is small).
  GLuint tiles_texture = 0;
  cv::Mat tiles;  ///< BGRA, the column's size
  std::string tiles_key;
  cv::Mat tile_picture;  ///< a picture scaled to its tile, reused
  /// The third-person view's picture, uploaded when it changes.
  GLuint third_texture = 0;
  int third_cols = 0, third_rows = 0;
  uint64_t third_id = 0;
};

Renderer::Renderer(int width, int height, const ScreenPlacement& screen)
    : width_(width), height_(height), screen_(screen), gl_(std::make_unique<Gl>()) {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (major * 10 + minor < 33) {
    throw ViewError("view: OpenGL 3.3 core is needed, this context has " + std::to_string(major) +
                    "." + std::to_string(minor));
  }
  Gl& g = *gl_;
  g.lit = Link(kLitVertex, kLitFragment);
  g.lit_mvp = glGetUniformLocation(g.lit, "mvp");
  glGenVertexArrays(1, &g.batch_vao);
  glGenBuffers(1, &g.batch_vbo);
  glGenBuffers(1, &g.batch_ebo);
  glBindVertexArray(g.batch_vao);
  glBindBuffer(GL_ARRAY_BUFFER, g.batch_vbo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.batch_ebo);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 10 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 10 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 10 * sizeof(float),
                        reinterpret_cast<void*>(6 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glBindVertexArray(0);
  g.batch.reserve(10 * 40000);
  g.batch_index.reserve(200000);
  g.lit_light = glGetUniformLocation(g.lit, "light_dir");
  g.tex = Link(kTexVertex, kTexFragment);
  g.tex_mvp = glGetUniformLocation(g.tex, "mvp");
  g.tex_image = glGetUniformLocation(g.tex, "image");
  g.tex_uv_rect = glGetUniformLocation(g.tex, "uv_rect");
  g.cube.Upload(CubeMesh(), false);
  g.sphere.Upload(SphereMesh(), false);
  g.cylinder.Upload(CylinderMesh(), false);
  g.screen.Upload(ScreenQuadMesh(), true);
  g.fullscreen.Upload(FullscreenQuadMesh(), true);

  auto make_texture = [](GLuint& t) {
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  };
  make_texture(g.video_texture);
  const uint8_t grey[3] = {40, 40, 40};  // no video yet: a dark screen
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, 1, 1, 0, GL_BGR, GL_UNSIGNED_BYTE, grey);
  make_texture(g.ghost_texture);
  make_texture(g.map_texture);
  make_texture(g.overlay_texture);
  g.overlay = cv::Mat(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, width, height, 0, GL_BGRA, GL_UNSIGNED_BYTE,
               g.overlay.data);
  make_texture(g.tiles_texture);  // its storage comes with the first tiles
  make_texture(g.third_texture);  // its storage comes with the first picture

  g.projection =
      Perspective(kFovYDeg, static_cast<float>(width) / static_cast<float>(height), kNear, kFar);
  g.view_projection = g.projection * LookAt(kEye, kTarget, Eigen::Vector3f::UnitZ());
  glViewport(0, 0, width, height);
}

Renderer::~Renderer() {
  Gl& g = *gl_;
  for (Mesh* m : {&g.cube, &g.sphere, &g.cylinder, &g.screen, &g.fullscreen}) m->Release();
  glDeleteBuffers(1, &g.batch_ebo);
  glDeleteBuffers(1, &g.batch_vbo);
  glDeleteVertexArrays(1, &g.batch_vao);
  glDeleteTextures(1, &g.video_texture);
  glDeleteTextures(1, &g.overlay_texture);
  glDeleteTextures(1, &g.ghost_texture);
  glDeleteTextures(1, &g.map_texture);
  glDeleteTextures(1, &g.tiles_texture);
  glDeleteTextures(1, &g.third_texture);
  glDeleteProgram(g.lit);
  glDeleteProgram(g.tex);
}

std::array<std::array<double, 3>, 4> Renderer::ScreenCorners() const {
  const auto& c = screen_.centre;
  const double hw = screen_.width / 2.0;
  const double hh = hw * screen_aspect_;
  std::array<std::array<double, 3>, 4> corners{{{c[0], c[1] + hw, c[2] + hh},
                                                {c[0], c[1] - hw, c[2] + hh},
                                                {c[0], c[1] - hw, c[2] - hh},
                                                {c[0], c[1] + hw, c[2] - hh}}};
  if (gaze_.tracked) {
    const Eigen::Quaternionf turn = Turn(gaze_.screen_pan, gaze_.screen_tilt);
    for (auto& corner : corners) corner = AboutEye(turn, corner);
  }
  return corners;
}

bool Renderer::Project(const std::array<double, 3>& point, double& px, double& py) const {
  const Eigen::Vector4f clip =
      gl_->view_projection * Eigen::Vector4f(static_cast<float>(point[0]),
                                             static_cast<float>(point[1]),
                                             static_cast<float>(point[2]), 1.0f);
  if (clip.w() <= 0.0f) return false;
  const double ndc_x = clip.x() / clip.w();
  const double ndc_y = clip.y() / clip.w();
  px = (ndc_x + 1.0) / 2.0 * width_;
  py = (1.0 - ndc_y) / 2.0 * height_;
  return true;
}

void Renderer::Draw(const ViewModel& model, double t_s) {
  Gl& g = *gl_;
  // A tracked gaze turns the view with the head and the screen with the camera.
  const bool was_tracked = gaze_.tracked;
  gaze_ = model.gaze;
  if (gaze_.tracked || was_tracked) {
    // A tracked head looks level when it looks ahead (a pilot's eyes, not a
    // desk's): the screen should hang at the eye's height in front of it.
    const Eigen::Vector3f target =
        gaze_.tracked ? Eigen::Vector3f(kEye + Turn(gaze_.look_pan, gaze_.look_tilt) *
                                                   Eigen::Vector3f::UnitX())
                      : kTarget;
    g.view_projection = g.projection * LookAt(kEye, target, Eigen::Vector3f::UnitZ());
  }
  const Eigen::Quaternionf screen_turn =
      gaze_.tracked ? Turn(gaze_.screen_pan, gaze_.screen_tilt) : Eigen::Quaternionf::Identity();
  const std::array<double, 4> screen_q{screen_turn.w(), screen_turn.x(), screen_turn.y(),
                                       screen_turn.z()};
  glViewport(0, 0, width_, height_);
  glClearColor(0.55f, 0.62f, 0.70f, 1.0f);  // a light room
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);  // few triangles: both sides cost nothing, and no winding to get wrong

  // --- Lit shapes: a floor and desk for depth, then the model's shapes. ---
  glUseProgram(g.lit);
  glEnable(GL_BLEND);  // the gesture wall is translucent
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUniform3f(g.lit_light, kLightDir.x(), kLightDir.y(), kLightDir.z());
  glUniformMatrix4fv(g.lit_mvp, 1, GL_FALSE, g.view_projection.data());
  g.batch.clear();
  g.batch_index.clear();
  auto draw = [&](const Mesh& mesh, const std::array<double, 3>& p, const std::array<double, 4>& q,
                  const Eigen::Vector3f& scale, const Rgba& color) {
    const Eigen::Matrix4f m = Model(p, q, scale);
    const Eigen::Matrix3f rs = m.block<3, 3>(0, 0);
    const Eigen::Matrix3f n = rs.inverse().transpose();
    const Eigen::Vector3f t = m.block<3, 1>(0, 3);
    const auto base = static_cast<uint32_t>(g.batch.size() / 10);
    const size_t count = mesh.unique.size() / 6;
    const size_t at = g.batch.size();
    g.batch.resize(at + 10 * count);
    float* out = g.batch.data() + at;
    const float* in = mesh.unique.data();
    for (size_t i = 0; i < count; ++i, in += 6, out += 10) {
      for (int r = 0; r < 3; ++r) {
        out[r] = rs(r, 0) * in[0] + rs(r, 1) * in[1] + rs(r, 2) * in[2] + t[r];
        out[3 + r] = n(r, 0) * in[3] + n(r, 1) * in[4] + n(r, 2) * in[5];
      }
      const float len = std::sqrt(out[3] * out[3] + out[4] * out[4] + out[5] * out[5]);
      const float inv = len > 0.0f ? 1.0f / len : 0.0f;
      out[3] *= inv;
      out[4] *= inv;
      out[5] *= inv;
      out[6] = color.r;
      out[7] = color.g;
      out[8] = color.b;
      out[9] = color.a;
    }
    for (const uint32_t k : mesh.index) g.batch_index.push_back(base + k);
  };
  const std::array<double, 4> identity{1, 0, 0, 0};
  draw(g.cube, {0.3, 0.0, -0.32}, identity, {3.0f, 3.0f, 0.01f},
       {0.35f, 0.36f, 0.38f, 1});  // floor
  const double screen_h = screen_.width * screen_aspect_;
  const auto& placed = screen_.centre;
  const std::array<double, 3> sc = AboutEye(screen_turn, placed);
  // The screen's bezel, just behind it.
  draw(g.cube, AboutEye(screen_turn, {placed[0] + 0.012, placed[1], placed[2]}), screen_q,
       {0.01f, static_cast<float>(screen_.width / 2 + 0.02),
        static_cast<float>(screen_h / 2 + 0.02)},
       {0.08f, 0.08f, 0.09f, 1});
  if (!gaze_.tracked) {  // a screen that turns with the camera hangs in the air
    draw(g.cube, {sc[0] + 0.03, sc[1], (sc[2] - screen_h / 2 + (-0.32)) / 2}, identity,
         {0.015f, 0.03f, static_cast<float>((sc[2] - screen_h / 2 + 0.32) / 2)},
         {0.1f, 0.1f, 0.1f, 1});  // its stand
  }

  for (const Shape& s : model.shapes) {
    const auto& z = s.size;
    switch (s.kind) {
      case ShapeKind::kBox:
        draw(g.cube, s.position, s.orientation,
             {static_cast<float>(z[0]), static_cast<float>(z[1]), static_cast<float>(z[2])},
             s.color);
        break;
      case ShapeKind::kSphere: {
        const auto r = static_cast<float>(z[0]);
        draw(g.sphere, s.position, s.orientation, {r, r, r}, s.color);
        break;
      }
      case ShapeKind::kCylinder:
      case ShapeKind::kCapsule: {
        const auto r = static_cast<float>(z[0]);
        const auto h = static_cast<float>(z[1]);
        draw(g.cylinder, s.position, s.orientation, {h, r, r}, s.color);
        if (s.kind == ShapeKind::kCapsule) {
          // The caps: spheres at ±h along the shape's own x axis.
          const Eigen::Quaternionf q(
              static_cast<float>(s.orientation[0]), static_cast<float>(s.orientation[1]),
              static_cast<float>(s.orientation[2]), static_cast<float>(s.orientation[3]));
          const Eigen::Vector3f axis = q.normalized() * Eigen::Vector3f(h, 0, 0);
          for (float sign : {-1.0f, 1.0f}) {
            const std::array<double, 3> p{s.position[0] + sign * axis.x(),
                                          s.position[1] + sign * axis.y(),
                                          s.position[2] + sign * axis.z()};
            draw(g.sphere, p, s.orientation, {r, r, r}, s.color);
          }
        }
        break;
      }
    }
  }

  glBindVertexArray(g.batch_vao);
  glBindBuffer(GL_ARRAY_BUFFER, g.batch_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(g.batch.size() * sizeof(float)),
               g.batch.data(), GL_STREAM_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(g.batch_index.size() * sizeof(uint32_t)),
               g.batch_index.data(), GL_STREAM_DRAW);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(g.batch_index.size()), GL_UNSIGNED_INT,
                 nullptr);
  glBindVertexArray(0);

  // --- The video screen. ---
  glUseProgram(g.tex);
  glActiveTexture(GL_TEXTURE0);
  glUniform1i(g.tex_image, 0);
  glUniform4f(g.tex_uv_rect, 0.0f, 0.0f, 1.0f, 1.0f);
  glBindTexture(GL_TEXTURE_2D, g.video_texture);
  const cv::Mat* image = model.video.image.get();
  if (image != nullptr && !image->empty() && image->type() == CV_8UC3 &&
      model.video.id != g.video_id) {
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(image->step / 3));
    if (image->cols != g.video_cols || image->rows != g.video_rows) {
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, image->cols, image->rows, 0, GL_BGR, GL_UNSIGNED_BYTE,
                   image->data);
      g.video_cols = image->cols;
      g.video_rows = image->rows;
      screen_aspect_ = static_cast<double>(image->rows) / image->cols;
    } else {
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image->cols, image->rows, GL_BGR, GL_UNSIGNED_BYTE,
                      image->data);
    }
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
    g.video_id = model.video.id;
  }
  {
    const double hw = screen_.width / 2.0;
    const Eigen::Matrix4f m = Model(
        sc, screen_q, {1.0f, static_cast<float>(hw), static_cast<float>(hw * screen_aspect_)});
    const Eigen::Matrix4f mvp = g.view_projection * m;
    glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, mvp.data());
    g.screen.Draw();
  }

  // --- The predictive display's ghost, in the picture on the screen. ---
  const Prediction& pr = model.prediction;
  if (pr.shown && g.video_cols > 0) {
    if (g.ghost.cols != g.video_cols || g.ghost.rows != g.video_rows) {
      g.ghost = cv::Mat(g.video_rows, g.video_cols, CV_8UC4, cv::Scalar(0, 0, 0, 0));
      g.ghost_rect = {};
      glBindTexture(GL_TEXTURE_2D, g.ghost_texture);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, g.ghost.cols, g.ghost.rows, 0, GL_BGRA,
                   GL_UNSIGNED_BYTE, g.ghost.data);
    }
    g.ghost(g.ghost_rect).setTo(cv::Scalar(0, 0, 0, 0));
    g.ghost_rect = DrawGhost(g.ghost, pr);
    const cv::Rect& r = g.ghost_rect;
    if (!r.empty()) {
      glBindTexture(GL_TEXTURE_2D, g.ghost_texture);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glPixelStorei(GL_UNPACK_ROW_LENGTH, g.ghost.cols);
      glTexSubImage2D(GL_TEXTURE_2D, 0, r.x, r.y, r.width, r.height, GL_BGRA, GL_UNSIGNED_BYTE,
                      g.ghost.ptr(r.y, r.x));
      glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
      // Only the rectangle holding the ghost, on the screen's own plane (the
      // unit quad's y and z run from the picture's left and top edges, +1,
      // to its right and bottom, -1), pulled a hair towards the eye so that
      // it wins the depth test against the picture and still loses it to a
      // hand in front of the screen.
      const double u0 = static_cast<double>(r.x) / g.ghost.cols,
                   u1 = static_cast<double>(r.x + r.width) / g.ghost.cols;
      const double v0 = static_cast<double>(r.y) / g.ghost.rows,
                   v1 = static_cast<double>(r.y + r.height) / g.ghost.rows;
      const double hw = screen_.width / 2.0;
      Eigen::Affine3f part = Eigen::Affine3f::Identity();
      part.translate(Eigen::Vector3f(0.0f, static_cast<float>(1.0 - (u0 + u1)),
                                     static_cast<float>(1.0 - (v0 + v1))));
      part.scale(Eigen::Vector3f(1.0f, static_cast<float>(u1 - u0), static_cast<float>(v1 - v0)));
      const Eigen::Matrix4f m =
          Model(sc, screen_q,
                {1.0f, static_cast<float>(hw), static_cast<float>(hw * screen_aspect_)}) *
          part.matrix();
      const Eigen::Matrix4f mvp = g.view_projection * m;
      glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, mvp.data());
      glUniform4f(g.tex_uv_rect, static_cast<float>(u0), static_cast<float>(v0),
                  static_cast<float>(u1 - u0), static_cast<float>(v1 - v0));
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(-1.0f, -1.0f);
      g.screen.Draw();
      glDisable(GL_POLYGON_OFFSET_FILL);
    }
  }

  // --- The overlay: redrawn on the CPU only when what it says changes. ---
  const Overlay& o = model.overlay;
  const bool lit = IndicatorLit(t_s);
  const std::vector<std::string> lines = OverlayLines(o);
  std::string key;
  for (const auto& l : lines) key += l + '\n';
  key += o.contact_now ? 'C' : '-';
  key += (o.hud && o.turn_left && lit) ? 'L' : '-';
  key += (o.hud && o.turn_right && lit) ? 'R' : '-';
  char needle[16];
  std::snprintf(needle, sizeof needle, "%.3f",
                o.hud ? o.speed_mps / std::max(o.speed_max_mps, 1e-3) : 0.0);
  key += needle;
  if (o.guidance_shown) {
    // The arrow's tip, formatted like the needle (GCC 12's -Wrestrict misreads
    // `"G" + std::to_string(...)` here).
    const GuidanceDial dial = GuidanceDialOf(o, width_, height_);
    char tip[32];
    std::snprintf(tip, sizeof tip, "G%d,%d", dial.tip_x, dial.tip_y);
    key += tip;
  }
  key += model.tiles.line;
  const cv::Mat* third = model.third_person.image.get();
  const bool third_shown = third != nullptr && !third->empty() && third->type() == CV_8UC3;
  key += third_shown ? 'T' : '-';
  glBindTexture(GL_TEXTURE_2D, g.overlay_texture);
  if (key != g.overlay_key) {
    g.overlay_key = key;
    cv::Mat& ov = g.overlay;
    ov.setTo(cv::Scalar(0, 0, 0, 0));
    g.overlay_rects.clear();
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    const double scale = 0.55 * height_ / 576.0;
    const int line_h = static_cast<int>(26 * height_ / 576.0);
    const int panel_lines = o.status[0] != '\0' ? 5 : 4;
    const cv::Rect panel(8, 8, static_cast<int>(width_ * 0.36), line_h * panel_lines + 12);
    cv::rectangle(ov, panel, Bgra(0, 0, 0, 150), cv::FILLED);
    g.overlay_rects.push_back(panel);
    for (int i = 0; i < panel_lines && i < static_cast<int>(lines.size()); ++i) {
      cv::putText(ov, lines[i], cv::Point(16, 8 + line_h * (i + 1)), font, scale,
                  Bgra(255, 255, 255), 1, cv::LINE_AA);
    }
    if (o.hud) {
      // Speedometer: a 240° dial at the bottom right (clear of the wheel),
      // the indicators above it, left and right.
      const int radius = static_cast<int>(58 * height_ / 576.0);
      const cv::Point centre(width_ - radius - 24, height_ - radius - 16);
      g.overlay_rects.emplace_back(centre.x - radius - 10, centre.y - radius - 60, 2 * radius + 20,
                                   2 * radius + 70);
      cv::circle(ov, centre, radius + 6, Bgra(20, 20, 20, 190), cv::FILLED, cv::LINE_AA);
      cv::ellipse(ov, centre, cv::Size(radius, radius), 0, 150, 390, Bgra(200, 200, 200), 2,
                  cv::LINE_AA);
      const double fraction =
          std::clamp(std::abs(o.speed_mps) / std::max(o.speed_max_mps, 1e-3), 0.0, 1.0);
      const double angle = (150.0 + 240.0 * fraction) * M_PI / 180.0;
      cv::line(ov, centre,
               centre + cv::Point(static_cast<int>(radius * 0.85 * std::cos(angle)),
                                  static_cast<int>(radius * 0.85 * std::sin(angle))),
               Bgra(40, 80, 255), 3, cv::LINE_AA);
      const std::string speed = HudSpeedText(o);
      int base = 0;
      const cv::Size ts = cv::getTextSize(speed, font, scale, 1, &base);
      cv::putText(ov, speed, centre + cv::Point(-ts.width / 2, radius / 2 + ts.height / 2), font,
                  scale, Bgra(255, 255, 255), 1, cv::LINE_AA);
      auto arrow = [&](int direction, bool on) {  // direction −1: left
        const cv::Point tip(centre.x + direction * (radius - 4), centre.y - radius - 34);
        const cv::Point pts[3] = {tip, tip + cv::Point(-direction * 26, -16),
                                  tip + cv::Point(-direction * 26, 16)};
        cv::fillConvexPoly(ov, pts, 3, on ? Bgra(60, 230, 60) : Bgra(60, 60, 60, 200), cv::LINE_AA);
      };
      arrow(-1, o.turn_left && lit);
      arrow(1, o.turn_right && lit);
      if (o.throttle_locked) {
        const cv::Point at(centre.x - radius - 190, height_ - 20);
        g.overlay_rects.emplace_back(at.x - 5, at.y - 25, 190, 35);
        cv::putText(ov, "THROTTLE LOCKED", at, font, scale, Bgra(0, 180, 255), 2, cv::LINE_AA);
      }
    }
    if (o.guidance_shown) {
      // Shared control's dial at the bottom left: the hand's plane seen from
      // above, the push on the hand as an orange arrow from its centre.
      const GuidanceDial d = GuidanceDialOf(o, width_, height_);
      const cv::Point centre(d.centre_x, d.centre_y), tip(d.tip_x, d.tip_y);
      g.overlay_rects.emplace_back(d.centre_x - d.radius - 8, d.centre_y - d.radius - 8,
                                   2 * d.radius + 16, 2 * d.radius + 16);
      cv::circle(ov, centre, d.radius + 6, Bgra(20, 20, 20, 190), cv::FILLED, cv::LINE_AA);
      cv::circle(ov, centre, d.radius, Bgra(120, 120, 120), 1, cv::LINE_AA);
      cv::line(ov, centre + cv::Point(0, -d.radius), centre + cv::Point(0, -d.radius + 8),
               Bgra(200, 200, 200), 2);
      if (tip != centre)
        cv::arrowedLine(ov, centre, tip, Bgra(0, 140, 255), 4, cv::LINE_AA, 0, 0.3);
    }
    if (o.message[0] != '\0') {
      int base = 0;
      const cv::Size ts = cv::getTextSize(o.message, font, scale * 1.2, 2, &base);
      const cv::Point at((width_ - ts.width) / 2, height_ - 24);
      const cv::Rect box(at.x - 8, at.y - ts.height - 8, ts.width + 16, ts.height + 16);
      cv::rectangle(ov, box, Bgra(0, 0, 0, 160), cv::FILLED);
      g.overlay_rects.push_back(box);
      cv::putText(ov, o.message, at, font, scale * 1.2, Bgra(255, 255, 255), 2, cv::LINE_AA);
    }
    if (model.tiles.count > 0 && model.tiles.line[0] != '\0') {
      // The fleet's line: bottom left, above the person's message.
      int base = 0;
      const cv::Size ts = cv::getTextSize(model.tiles.line, font, scale, 1, &base);
      const cv::Point at(16, height_ - 24 - 2 * line_h);
      const cv::Rect box(at.x - 8, at.y - ts.height - 8, ts.width + 16, ts.height + 16);
      cv::rectangle(ov, box, Bgra(0, 0, 0, 160), cv::FILLED);
      g.overlay_rects.push_back(box);
      cv::putText(ov, model.tiles.line, at, font, scale,
                  Bgra(kTileFrameBgr[0], kTileFrameBgr[1], kTileFrameBgr[2]), 1, cv::LINE_AA);
    }
    if (third_shown) {
      // The third-person view's frame and label; its picture goes over the frame.
      const TileBox label = ThirdPersonLabelRect(width_, height_);
      const TileBox picture = ThirdPersonRect(width_, height_);
      const cv::Rect frame(label.x - 3, label.y, label.width + 6,
                           label.height + picture.height + 3);
      cv::rectangle(ov, frame, Bgra(0, 0, 0, 200), cv::FILLED);
      g.overlay_rects.push_back(frame);
      cv::putText(ov, kThirdPersonLabel, cv::Point(label.x + 4, label.y + label.height - 6), font,
                  0.5 * height_ / 576.0, Bgra(255, 255, 255), 1, cv::LINE_AA);
    }
    if (o.contact_now) {
      cv::rectangle(ov, cv::Rect(0, 0, width_, height_), Bgra(0, 0, 255, 220), 10);
      const int b = 8;
      g.overlay_rects.emplace_back(0, 0, width_, b);
      g.overlay_rects.emplace_back(0, height_ - b, width_, b);
      g.overlay_rects.emplace_back(0, 0, b, height_);
      g.overlay_rects.emplace_back(width_ - b, 0, b, height_);
    }
    const cv::Rect frame(0, 0, width_, height_);
    for (cv::Rect& r : g.overlay_rects) r &= frame;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width_, height_, GL_BGRA, GL_UNSIGNED_BYTE, ov.data);
  }
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  for (const cv::Rect& r : g.overlay_rects) {
    const float w = static_cast<float>(width_), h = static_cast<float>(height_);
    const Eigen::Matrix4f m = PixelRect(r.x, r.y, r.width, r.height, width_, height_);
    glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, m.data());
    glUniform4f(g.tex_uv_rect, static_cast<float>(r.x) / w, static_cast<float>(r.y) / h,
                static_cast<float>(r.width) / w, static_cast<float>(r.height) / h);
    g.fullscreen.Draw();
  }

  // --- The third-person view's picture, in its frame under the overlay's
  // panel: uploaded only when a new one came. ---
  if (third_shown) {
    glBindTexture(GL_TEXTURE_2D, g.third_texture);
    if (model.third_person.id != g.third_id || third->cols != g.third_cols ||
        third->rows != g.third_rows) {
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(third->step / 3));
      if (third->cols != g.third_cols || third->rows != g.third_rows) {
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, third->cols, third->rows, 0, GL_BGR,
                     GL_UNSIGNED_BYTE, third->data);
        g.third_cols = third->cols;
        g.third_rows = third->rows;
      } else {
        glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, third->cols, third->rows, GL_BGR, GL_UNSIGNED_BYTE,
                        third->data);
      }
      glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
      g.third_id = model.third_person.id;
    }
    const TileBox r = ThirdPersonRect(width_, height_);
    const Eigen::Matrix4f m = PixelRect(r.x, r.y, r.width, r.height, width_, height_);
    glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, m.data());
    glUniform4f(g.tex_uv_rect, 0.0f, 0.0f, 1.0f, 1.0f);
    g.fullscreen.Draw();
  }

  // --- A fleet's tiles, down the right edge: each vehicle's picture, its
  // name, state and lap; the driven one framed. ---
  const Tiles& tiles = model.tiles;
  const int tile_count = std::clamp(tiles.count, 0, Tiles::kMax);
  if (tile_count > 0) {
    const TileBox first = TileRect(0, tile_count, width_, height_);
    const TileBox last = TileRect(tile_count - 1, tile_count, width_, height_);
    const cv::Rect column(first.x, first.y, first.width, last.y + last.height - first.y);
    std::string tiles_key;
    for (int i = 0; i < tile_count; ++i) {
      tiles_key += TileText(tiles.tile[static_cast<size_t>(i)]);
      tiles_key += '#' + std::to_string(model.tile_video[static_cast<size_t>(i)].id) + '\n';
    }
    if (tiles_key != g.tiles_key || g.tiles.size() != column.size()) {
      g.tiles_key = tiles_key;
      if (g.tiles.size() != column.size()) g.tiles = cv::Mat(column.height, column.width, CV_8UC4);
      g.tiles.setTo(cv::Scalar(0, 0, 0, 0));
      const double text = 0.40 * height_ / 576.0;
      for (int i = 0; i < tile_count; ++i) {
        const Tiles::Tile& tile = tiles.tile[static_cast<size_t>(i)];
        const TileBox box = TileRect(i, tile_count, width_, height_);
        const cv::Rect at(box.x - column.x, box.y - column.y, box.width, box.height);
        const int picture_h = box.width * 3 / 4;
        const cv::Rect picture(at.x, at.y, at.width, picture_h);
        cv::rectangle(g.tiles, at, Bgra(0, 0, 0, 190), cv::FILLED);
        const cv::Mat* image = model.tile_video[static_cast<size_t>(i)].image.get();
        if (image != nullptr && !image->empty() && image->type() == CV_8UC3) {
          cv::resize(*image, g.tile_picture, picture.size(), 0, 0, cv::INTER_AREA);
          cv::cvtColor(g.tile_picture, g.tiles(picture), cv::COLOR_BGR2BGRA);
        } else {
          cv::rectangle(g.tiles, picture, Bgra(40, 40, 40), cv::FILLED);
        }
        if (tile.state == TileState::kLost) {
          // Its last picture is stale: crossed out.
          cv::line(g.tiles, picture.tl(), picture.br(), Bgra(0, 0, 255), 3, cv::LINE_AA);
          cv::line(g.tiles, cv::Point(picture.x + picture.width, picture.y),
                   cv::Point(picture.x, picture.y + picture.height), Bgra(0, 0, 255), 3,
                   cv::LINE_AA);
        }
        cv::putText(g.tiles, TileText(tile), cv::Point(at.x + 4, at.y + at.height - 6),
                    cv::FONT_HERSHEY_SIMPLEX, text, Bgra(255, 255, 255), 1, cv::LINE_AA);
        if (tile.state == TileState::kDriven) {
          cv::rectangle(g.tiles, at, Bgra(kTileFrameBgr[0], kTileFrameBgr[1], kTileFrameBgr[2]), 4);
        }
      }
      glBindTexture(GL_TEXTURE_2D, g.tiles_texture);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, g.tiles.cols, g.tiles.rows, 0, GL_BGRA,
                   GL_UNSIGNED_BYTE, g.tiles.data);
    }
    glBindTexture(GL_TEXTURE_2D, g.tiles_texture);
    const Eigen::Matrix4f m =
        PixelRect(column.x, column.y, column.width, column.height, width_, height_);
    glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, m.data());
    glUniform4f(g.tex_uv_rect, 0.0f, 0.0f, 1.0f, 1.0f);
    g.fullscreen.Draw();
  }

  // --- The predictive display's map, top right: the track drawn once, the
  // poses over it each frame. ---
  g.map_drawn = false;
  if (pr.shown && model.map) {
    const int side = static_cast<int>(0.36 * height_);
    const int line_h = static_cast<int>(18 * height_ / 576.0);
    // A flying vehicle's heights take a third line under the legend.
    const int lines = pr.heights ? 3 : 2;
    const cv::Rect panel(width_ - side - 8, 8, side, side + lines * line_h + 6);
    if (g.map_of != model.map.get() || g.map_base.size() != panel.size()) {
      g.map_of = model.map.get();
      g.map_base = cv::Mat(panel.height, panel.width, CV_8UC4, Bgra(0, 0, 0, 170));
      FitMap(*model.map, side, g.map_scale, g.map_ox, g.map_oy);
      const auto px = [&](double x, double y) {
        return Fixed(g.map_ox + g.map_scale * x - 0.5, g.map_oy - g.map_scale * y - 0.5);
      };
      for (const TrackMap::Line& l : model.map->walls) {
        cv::line(g.map_base, px(l.ax, l.ay), px(l.bx, l.by), Bgra(200, 200, 200), 1, cv::LINE_AA,
                 kShift);
      }
      const TrackMap::Line& st = model.map->start;
      cv::line(g.map_base, px(st.ax, st.ay), px(st.bx, st.by), Bgra(120, 120, 120), 1, cv::LINE_AA,
               kShift);
      for (const TrackMap::Line& l : model.map->gates) {
        cv::line(g.map_base, px(l.ax, l.ay), px(l.bx, l.by), Bgra(0, 200, 230), 1, cv::LINE_AA,
                 kShift);
      }
      for (const TrackMap::Post& p : model.map->posts) {
        const bool landing = p.kind == TrackMap::PostKind::kLanding;
        const cv::Scalar c = p.kind == TrackMap::PostKind::kLeft    ? Bgra(40, 40, 225)
                             : p.kind == TrackMap::PostKind::kRight ? Bgra(50, 200, 40)
                             : landing                              ? Bgra(120, 220, 120)
                                                                    : Bgra(0, 140, 255);
        cv::circle(g.map_base, px(p.x, p.y),
                   static_cast<int>(std::max(2.0, p.radius * g.map_scale) * kOne), c,
                   landing ? 1 : cv::FILLED, cv::LINE_AA, kShift);
      }
      const double text = 0.42 * height_ / 576.0;
      for (const TrackMap::Label& l : model.map->labels) {
        // Right of the place, or left of it where the panel ends.
        int baseline = 0;
        const cv::Size size =
            cv::getTextSize(l.text, cv::FONT_HERSHEY_SIMPLEX, 0.85 * text, 1, &baseline);
        const int x = static_cast<int>(g.map_ox + g.map_scale * l.x);
        const cv::Point at(x + 4 + size.width < side ? x + 4 : std::max(0, x - 4 - size.width),
                           static_cast<int>(g.map_oy - g.map_scale * l.y) - 4);
        cv::putText(g.map_base, l.text, at, cv::FONT_HERSHEY_SIMPLEX, 0.85 * text,
                    Bgra(0, 200, 230), 1, cv::LINE_AA);
      }
      cv::circle(g.map_base, cv::Point(10, side + line_h - 4), 4, kReported, 2, cv::LINE_AA);
      cv::putText(g.map_base, "as last reported", cv::Point(20, side + line_h),
                  cv::FONT_HERSHEY_SIMPLEX, text, kReported, 1, cv::LINE_AA);
      cv::circle(g.map_base, cv::Point(10, side + 2 * line_h - 4), 5, kGhostLine, cv::FILLED,
                 cv::LINE_AA);
    }
    g.map_base.copyTo(g.map);
    const auto px = [&](double x, double y) {
      return Fixed(g.map_ox + g.map_scale * x - 0.5, g.map_oy - g.map_scale * y - 0.5);
    };
    const double body = std::max(4.0, pr.body_radius * g.map_scale);
    // A pose: its body to scale (at least a few pixels), a tick to the rim
    // for its heading; the path ahead runs on beyond the predicted one.
    const auto pose = [&](const MapPose& p, const cv::Scalar& c, const cv::Scalar& tick,
                          bool filled) {
      const cv::Point centre = px(p.x, p.y);
      const double reach = body / g.map_scale;
      const cv::Point nose =
          px(p.x + reach * std::cos(p.heading), p.y + reach * std::sin(p.heading));
      cv::circle(g.map, centre, static_cast<int>(body * kOne), c, filled ? cv::FILLED : 2,
                 cv::LINE_AA, kShift);
      cv::line(g.map, centre, nose, tick, 2, cv::LINE_AA, kShift);
    };
    const int n = std::clamp(pr.map_path_count, 0, Prediction::kPathMax);
    for (int i = 1; i < n; ++i) {
      const MapPose& a = pr.map_path[static_cast<size_t>(i - 1)];
      const MapPose& b = pr.map_path[static_cast<size_t>(i)];
      cv::line(g.map, px(a.x, a.y), px(b.x, b.y), kGhostLine, 2, cv::LINE_AA, kShift);
    }
    pose(pr.reported, kReported, kReported, false);
    pose(pr.predicted, kGhostLine, Bgra(40, 0, 40), true);
    char label[64];
    std::snprintf(label, sizeof label, "now, +%.0f ms; path: 1 s", pr.one_way_delay_s * 1e3);
    cv::putText(g.map, label, cv::Point(20, side + 2 * line_h), cv::FONT_HERSHEY_SIMPLEX,
                0.42 * height_ / 576.0, kGhostLine, 1, cv::LINE_AA);
    if (pr.heights && n > 0) {
      // A flying vehicle: where it was, is and will be, in height (the map
      // is seen from above).
      std::snprintf(label, sizeof label, "height: was %.2f, now %.2f, in 1 s %.2f m",
                    static_cast<double>(pr.reported.z), static_cast<double>(pr.predicted.z),
                    static_cast<double>(pr.map_path[static_cast<size_t>(n - 1)].z));
      // Smaller where the panel is too narrow for it.
      double scale = 0.42 * height_ / 576.0;
      int baseline = 0;
      const int wide = cv::getTextSize(label, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &baseline).width;
      if (wide > side - 24) scale *= static_cast<double>(side - 24) / wide;
      cv::putText(g.map, label, cv::Point(20, side + 3 * line_h), cv::FONT_HERSHEY_SIMPLEX, scale,
                  kGhostLine, 1, cv::LINE_AA);
    }
    glBindTexture(GL_TEXTURE_2D, g.map_texture);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, g.map.cols, g.map.rows, 0, GL_BGRA, GL_UNSIGNED_BYTE,
                 g.map.data);
    const Eigen::Matrix4f m =
        PixelRect(panel.x, panel.y, panel.width, panel.height, width_, height_);
    glUniformMatrix4fv(g.tex_mvp, 1, GL_FALSE, m.data());
    glUniform4f(g.tex_uv_rect, 0.0f, 0.0f, 1.0f, 1.0f);
    g.fullscreen.Draw();
    g.map_panel = panel;
    g.map_drawn = true;
  }
  glDisable(GL_BLEND);
  glBindVertexArray(0);
}

bool Renderer::MapPoint(double x, double y, double& px, double& py) const {
  const Gl& g = *gl_;
  if (!g.map_drawn) return false;
  px = g.map_panel.x + g.map_ox + g.map_scale * x;
  py = g.map_panel.y + g.map_oy - g.map_scale * y;
  return true;
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
