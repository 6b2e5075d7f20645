#include "world_layer.hpp"

#include <cmath>

namespace haptel::view::layers {
namespace {

const Eigen::Vector3f kLightDir =
    Eigen::Vector3f(0.3f, -0.2f, -1.0f).normalized();  // pointing down

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

}  // namespace

WorldLayer::WorldLayer(const VideoScreen& screen) : screen_(screen) {
  program_ = LinkProgram(kLitVertex, kLitFragment);
  mvp_ = glGetUniformLocation(program_, "mvp");
  light_ = glGetUniformLocation(program_, "light_dir");
  glGenVertexArrays(1, &batch_vao_);
  glGenBuffers(1, &batch_vbo_);
  glGenBuffers(1, &batch_ebo_);
  glBindVertexArray(batch_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, batch_vbo_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, batch_ebo_);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 10 * sizeof(float), nullptr);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 10 * sizeof(float),
                        reinterpret_cast<void*>(3 * sizeof(float)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(2, 4, GL_FLOAT, GL_FALSE, 10 * sizeof(float),
                        reinterpret_cast<void*>(6 * sizeof(float)));
  glEnableVertexAttribArray(2);
  glBindVertexArray(0);
  batch_.reserve(10 * 40000);
  batch_index_.reserve(200000);
  cube_.Upload(CubeMesh(), false);
  sphere_.Upload(SphereMesh(), false);
  cylinder_.Upload(CylinderMesh(), false);
}

WorldLayer::~WorldLayer() {
  for (Mesh* m : {&cube_, &sphere_, &cylinder_}) m->Release();
  glDeleteBuffers(1, &batch_ebo_);
  glDeleteBuffers(1, &batch_vbo_);
  glDeleteVertexArrays(1, &batch_vao_);
  glDeleteProgram(program_);
}

void WorldLayer::Add(const Mesh& mesh, const std::array<double, 3>& position,
                     const std::array<double, 4>& orientation, const Eigen::Vector3f& scale,
                     const Rgba& color) {
  const Eigen::Matrix4f m = Model(position, orientation, scale);
  const Eigen::Matrix3f rs = m.block<3, 3>(0, 0);
  const Eigen::Matrix3f n = rs.inverse().transpose();
  const Eigen::Vector3f t = m.block<3, 1>(0, 3);
  const auto base = static_cast<uint32_t>(batch_.size() / 10);
  const size_t count = mesh.unique.size() / 6;
  const size_t at = batch_.size();
  batch_.resize(at + 10 * count);
  float* out = batch_.data() + at;
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
  for (const uint32_t k : mesh.index) batch_index_.push_back(base + k);
}

void WorldLayer::AddRoom(bool gaze_tracked) {
  const std::array<double, 4> identity{1, 0, 0, 0};
  Add(cube_, {0.3, 0.0, -0.32}, identity, {3.0f, 3.0f, 0.01f}, {0.35f, 0.36f, 0.38f, 1});  // floor
  const ScreenPlacement& placed = screen_.placement;
  const double screen_h = placed.width * screen_.aspect;
  const std::array<double, 3> sc = screen_.Centre();
  // The screen's bezel, just behind it.
  Add(cube_, screen_.AboutEyeOf({placed.centre[0] + 0.012, placed.centre[1], placed.centre[2]}),
      screen_.Orientation(),
      {0.01f, static_cast<float>(placed.width / 2 + 0.02), static_cast<float>(screen_h / 2 + 0.02)},
      {0.08f, 0.08f, 0.09f, 1});
  if (!gaze_tracked) {  // a screen that turns with the camera hangs in the air
    Add(cube_, {sc[0] + 0.03, sc[1], (sc[2] - screen_h / 2 + (-0.32)) / 2}, identity,
        {0.015f, 0.03f, static_cast<float>((sc[2] - screen_h / 2 + 0.32) / 2)},
        {0.1f, 0.1f, 0.1f, 1});  // its stand
  }
}

void WorldLayer::AddShape(const Shape& s) {
  const auto& z = s.size;
  switch (s.kind) {
    case ShapeKind::kBox:
      Add(cube_, s.position, s.orientation,
          {static_cast<float>(z[0]), static_cast<float>(z[1]), static_cast<float>(z[2])}, s.color);
      break;
    case ShapeKind::kSphere: {
      const auto r = static_cast<float>(z[0]);
      Add(sphere_, s.position, s.orientation, {r, r, r}, s.color);
      break;
    }
    case ShapeKind::kCylinder:
    case ShapeKind::kCapsule: {
      const auto r = static_cast<float>(z[0]);
      const auto h = static_cast<float>(z[1]);
      Add(cylinder_, s.position, s.orientation, {h, r, r}, s.color);
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
          Add(sphere_, p, s.orientation, {r, r, r}, s.color);
        }
      }
      break;
    }
  }
}

void WorldLayer::Draw(const ViewModel& model, const Frame& frame) {
  glUseProgram(program_);
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_BLEND);  // the gesture wall is translucent
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  glUniform3f(light_, kLightDir.x(), kLightDir.y(), kLightDir.z());
  glUniformMatrix4fv(mvp_, 1, GL_FALSE, frame.view_projection.data());
  batch_.clear();
  batch_index_.clear();
  AddRoom(model.gaze.tracked);
  for (const Shape& s : model.shapes) AddShape(s);

  glBindVertexArray(batch_vao_);
  glBindBuffer(GL_ARRAY_BUFFER, batch_vbo_);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(batch_.size() * sizeof(float)),
               batch_.data(), GL_STREAM_DRAW);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(batch_index_.size() * sizeof(uint32_t)), batch_index_.data(),
               GL_STREAM_DRAW);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(batch_index_.size()), GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
}

}  // namespace haptel::view::layers
