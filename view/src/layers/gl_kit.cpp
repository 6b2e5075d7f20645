#include "gl_kit.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "haptel/view/view.hpp"

namespace haptel::view::layers {
namespace {

const char* kTexturedVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec2 uv;
uniform mat4 mvp;
uniform vec4 uv_rect;  // offset (xy) and scale (zw) of the texture window
out vec2 tex_uv;
void main() {
  gl_Position = mvp * vec4(position, 1.0);
  tex_uv = uv_rect.xy + uv * uv_rect.zw;
})";

const char* kTexturedFragment = R"(#version 330 core
in vec2 tex_uv;
uniform sampler2D image;
out vec4 frag;
void main() { frag = texture(image, tex_uv); })";

/// Throws ViewError with GL's log, deleting `object`, when its `status`
/// (a shader's compile, a program's link) failed.
void Check(GLuint object, GLenum status, decltype(&glGetShaderiv) get,
           decltype(&glGetShaderInfoLog) get_log, decltype(&glDeleteShader) release,
           const char* failed) {
  GLint ok = 0;
  get(object, status, &ok);
  if (ok != 0) return;
  char log[1024] = "";
  get_log(object, sizeof log, nullptr, log);
  release(object);
  throw ViewError(std::string("view: ") + failed + ": " + log);
}

GLuint Compile(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  Check(shader, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader,
        "shader does not compile");
  return shader;
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

}  // namespace

GLuint LinkProgram(const char* vertex_source, const char* fragment_source) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex_source);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, fragment_source);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  Check(program, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram,
        "shader program does not link");
  return program;
}

void Mesh::Upload(const std::vector<float>& data, bool textured) {
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

void Mesh::Release() {
  if (ebo != 0) glDeleteBuffers(1, &ebo);
  if (vbo != 0) glDeleteBuffers(1, &vbo);
  if (vao != 0) glDeleteVertexArrays(1, &vao);
  ebo = vbo = vao = 0;
}

void Mesh::Draw() const {
  glBindVertexArray(vao);
  glDrawElements(GL_TRIANGLES, indices, GL_UNSIGNED_INT, nullptr);
}

GLuint MakeTexture() {
  GLuint t = 0;
  glGenTextures(1, &t);
  glBindTexture(GL_TEXTURE_2D, t);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return t;
}

void UploadBgr(const cv::Mat& bgr, int& cols, int& rows) {
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, static_cast<GLint>(bgr.step / 3));
  if (bgr.cols != cols || bgr.rows != rows) {
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB8, bgr.cols, bgr.rows, 0, GL_BGR, GL_UNSIGNED_BYTE,
                 bgr.data);
    cols = bgr.cols;
    rows = bgr.rows;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, bgr.cols, bgr.rows, GL_BGR, GL_UNSIGNED_BYTE, bgr.data);
  }
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
}

void UploadBgra(const cv::Mat& bgra) {
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, bgra.cols, bgra.rows, 0, GL_BGRA, GL_UNSIGNED_BYTE,
               bgra.data);
}

TexturedQuads::TexturedQuads() {
  program_ = LinkProgram(kTexturedVertex, kTexturedFragment);
  mvp_ = glGetUniformLocation(program_, "mvp");
  uv_rect_ = glGetUniformLocation(program_, "uv_rect");
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "image"), 0);  // texture unit 0, always
  glUseProgram(0);
  screen_.Upload(ScreenQuadMesh(), true);
  fullscreen_.Upload(FullscreenQuadMesh(), true);
}

TexturedQuads::~TexturedQuads() {
  screen_.Release();
  fullscreen_.Release();
  glDeleteProgram(program_);
}

void TexturedQuads::BeginInWorld() const {
  glUseProgram(program_);
  glActiveTexture(GL_TEXTURE0);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
}

void TexturedQuads::BeginOverWorld() const {
  glUseProgram(program_);
  glActiveTexture(GL_TEXTURE0);
  glDisable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
}

void TexturedQuads::DrawScreenQuad(const Eigen::Matrix4f& mvp,
                                   const std::array<float, 4>& uv) const {
  glUniformMatrix4fv(mvp_, 1, GL_FALSE, mvp.data());
  glUniform4f(uv_rect_, uv[0], uv[1], uv[2], uv[3]);
  screen_.Draw();
}

void TexturedQuads::DrawPixels(const cv::Rect& rect, int view_width, int view_height,
                               const std::array<float, 4>& uv) const {
  const Eigen::Matrix4f m =
      PixelRect(rect.x, rect.y, rect.width, rect.height, view_width, view_height);
  glUniformMatrix4fv(mvp_, 1, GL_FALSE, m.data());
  glUniform4f(uv_rect_, uv[0], uv[1], uv[2], uv[3]);
  fullscreen_.Draw();
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

Eigen::Quaternionf Turn(double pan, double tilt) {
  return Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(pan), Eigen::Vector3f::UnitZ()) *
                            Eigen::AngleAxisf(static_cast<float>(-tilt), Eigen::Vector3f::UnitY()));
}

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

cv::Point Fixed(double x, double y) {
  const auto fix = [](double c) {
    return static_cast<int>(std::lround(std::clamp(c, -1e5, 1e5) * kOne));
  };
  return {fix(x), fix(y)};
}

}  // namespace haptel::view::layers
