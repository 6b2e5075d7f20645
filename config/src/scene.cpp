#include "haptel/config/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>

#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/yaml_map.hpp"
#include "haptel/geometry/mass_properties.hpp"
#include "scene_detail.hpp"

namespace haptel {

using config_detail::YamlMap;
using Eigen::Matrix3d;
using Eigen::Vector3d;

// ---- materials -----------------------------------------------------------
//
// Friction: dry, clean surfaces of the material against itself, from
// Serway & Jewett, "Physics for Scientists and Engineers", Table 5.1
// (steel, glass, wood, ice; aluminium) and the Engineering ToolBox table
// "Friction and Friction Coefficients for some Common Materials" (brick).
// Marble and carpet have no standard table entry: their values are estimates
// from floor slip-resistance measurements (dry polished stone ≈ 0.5, dry
// carpet ≈ 0.6–0.8). Clean aluminium on aluminium galls (μs 1.05–1.35 in the
// tables), which handled objects do not: the aluminium-on-steel pair is used.
// Restitution: approximate low-speed (≈ 1 m/s) values of common drop tests;
// it depends strongly on speed and geometry, so treat it as a feel setting.
// All values approximate.
namespace {
struct Preset {
  const char* name;
  Material material;
};
constexpr Preset kPresets[] = {
    {"wood", {0.5, 0.4, 0.2}},         // wood/wood μs 0.25–0.5, μk 0.2
    {"marble", {0.6, 0.5, 0.4}},       // estimate (polished stone)
    {"brick", {0.3, 0.6, 0.5}},        // brick/masonry μs ≈ 0.6; μk estimate
    {"steel", {0.6, 0.74, 0.57}},      // mild steel/steel
    {"aluminium", {0.5, 0.61, 0.47}},  // aluminium/steel
    {"glass", {0.7, 0.94, 0.4}},       // glass/glass
    {"carpet", {0.1, 0.8, 0.6}},       // estimate (slip-resistance tests)
    {"ice", {0.3, 0.1, 0.03}},         // ice/ice at 0 °C
};
}  // namespace

std::optional<Material> MaterialPreset(const std::string& name) {
  for (const Preset& p : kPresets) {
    if (name == p.name) return p.material;
  }
  return std::nullopt;
}

const std::vector<std::string>& MaterialPresetNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Preset& p : kPresets) out.emplace_back(p.name);
    return out;
  }();
  return names;
}

Material CombineMaterials(const Material& a, const Material& b) {
  return {0.5 * (a.restitution + b.restitution), 0.5 * (a.static_friction + b.static_friction),
          0.5 * (a.dynamic_friction + b.dynamic_friction)};
}

const char* ShapeKindName(ShapeKind kind) {
  switch (kind) {
    case ShapeKind::kBox:
      return "box";
    case ShapeKind::kSphere:
      return "sphere";
    case ShapeKind::kCapsule:
      return "capsule";
    case ShapeKind::kPlane:
      return "plane";
    case ShapeKind::kConvex:
      return "convex";
  }
  return "?";
}

SceneNodeOrder OrderNodes(const Scene& scene) {
  SceneNodeOrder order;
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].dynamic) order.objects.push_back(i);
  }
  order.dynamic_count = order.objects.size();
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    if (!scene.objects[i].dynamic) order.objects.push_back(i);
  }
  return order;
}

// ---- shared validation ------------------------------------------------------

namespace config_detail {

std::string ToRotation(const std::vector<double>& rows, Matrix3d& out) {
  Matrix3d m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m(r, c) = rows[static_cast<size_t>(3 * r + c)];
  }
  if ((m * m.transpose() - Matrix3d::Identity()).cwiseAbs().maxCoeff() > 2e-3 ||
      m.determinant() <= 0.0) {
    return "a rotation matrix (orthonormal rows, determinant +1; 9 numbers row by row)";
  }
  const Eigen::JacobiSVD<Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  out = svd.matrixU() * svd.matrixV().transpose();
  return "";
}

std::string CheckMassProperties(const SceneObject& object) {
  try {
    const MassProperties p = ComputeMassProperties(object);
    if (!(p.mass > 0.0) || !p.inertia.allFinite() ||
        !(Diagonalize(p.inertia).moments.minCoeff() > 0.0)) {
      return "shapes giving a positive mass and inertia";
    }
  } catch (const std::invalid_argument& e) {
    return std::string("shapes with valid mass properties (") + e.what() + ")";
  }
  return "";
}

}  // namespace config_detail

// ---- YAML ------------------------------------------------------------------

namespace {

using namespace config_detail;

const char* const kPresetList = "wood, marble, brick, steel, aluminium, glass, carpet, ice";

std::string QuaternionToRotation(const std::vector<double>& wxyz, Matrix3d& out) {
  Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  if (std::abs(q.norm() - 1.0) > 1e-3) return "a unit quaternion [w, x, y, z]";
  out = q.normalized().toRotationMatrix();
  return "";
}

Matrix3d ReadRotation(YamlMap& map) {
  Matrix3d out = Matrix3d::Identity();
  const bool has_matrix = map.Has("rotation");
  const bool has_quaternion = map.Has("quaternion_wxyz");
  if (has_matrix && has_quaternion)
    map.Fail("quaternion_wxyz", "either 'rotation' or 'quaternion_wxyz', not both");
  if (has_matrix) {
    const std::string problem = ToRotation(map.Numbers("rotation", 9, -1.01, 1.01), out);
    if (!problem.empty()) map.Fail("rotation", problem);
  } else if (has_quaternion) {
    const std::string problem =
        QuaternionToRotation(map.Numbers("quaternion_wxyz", 4, -1.01, 1.01), out);
    if (!problem.empty()) map.Fail("quaternion_wxyz", problem);
  }
  return out;
}

Vector3d ToVector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
Vector3d ToVector(const std::vector<double>& a) { return {a[0], a[1], a[2]}; }

// `points` of a convex shape, which must span a volume.
std::vector<Vector3d> ReadConvexPoints(YamlMap& shape) {
  std::vector<Vector3d> points;
  for (const auto& p : shape.Points3("points", 4, kMaxConvexPoints, kMaxSize))
    points.emplace_back(p[0], p[1], p[2]);
  try {
    ComputeConvexHull(points);
  } catch (const std::invalid_argument& e) {
    shape.Fail("points", std::string("points spanning a volume (") + e.what() + ")");
  }
  return points;
}

SceneShape ReadShape(YamlMap& s, bool dynamic) {
  SceneShape shape;
  const std::string type = s.RequireString("type");
  const std::string kinds = "one of: box, sphere, capsule, plane, convex";
  if (type == "box") {
    shape.kind = ShapeKind::kBox;
    const bool half = s.Has("half_extents");
    const bool full = s.Has("size");
    if (half == full) s.Fail("size", "exactly one of 'half_extents' and 'size' for a box");
    shape.half_extents =
        half ? ToVector(s.Numbers("half_extents", 3, kMinSize, kMaxSize))
             : Vector3d(0.5 * ToVector(s.Numbers("size", 3, 2 * kMinSize, 2 * kMaxSize)));
  } else if (type == "sphere") {
    shape.kind = ShapeKind::kSphere;
    shape.radius = s.RequireNumber("radius", kMinSize, kMaxSize);
  } else if (type == "capsule") {
    shape.kind = ShapeKind::kCapsule;
    shape.radius = s.RequireNumber("radius", kMinSize, kMaxSize);
    shape.length = s.RequireNumber("length", 0.0, kMaxSize);
  } else if (type == "plane") {
    shape.kind = ShapeKind::kPlane;
    if (dynamic) s.Fail("type", "box, sphere, capsule or convex: planes only on static objects");
    const Vector3d n = ToVector(s.Numbers("normal", 3, -kMaxSize, kMaxSize));
    if (n.norm() < 1e-9) s.Fail("normal", "a non-zero normal vector");
    shape.normal = n.normalized();
    shape.offset = s.RequireNumber("offset", -kMaxCoordinate, kMaxCoordinate) / n.norm();
  } else if (type == "convex") {
    shape.kind = ShapeKind::kConvex;
    shape.points = ReadConvexPoints(s);
  } else {
    s.Fail("type", kinds);
  }
  shape.position = ToVector(s.Vec3("position", {0.0, 0.0, 0.0}, -kMaxCoordinate, kMaxCoordinate));
  shape.rotation = ReadRotation(s);
  s.Finish();
  return shape;
}

Material ReadMaterial(YamlMap& o) {
  if (!o.Has("material")) return Material{};
  const std::string expected = std::string("a preset (") + kPresetList +
                               ") or a mapping {restitution, static_friction, dynamic_friction}";
  if (o.IsScalar("material")) {
    const std::string name = o.String("material", "");
    const auto preset = MaterialPreset(name);
    if (!preset) o.Fail("material", expected);
    return *preset;
  }
  if (!o.IsMap("material")) o.Fail("material", expected);
  YamlMap m = o.Map("material");
  Material out;
  out.restitution = m.RequireNumber("restitution", 0.0, 1.0);
  out.static_friction = m.RequireNumber("static_friction", 0.0, kMaxFriction);
  out.dynamic_friction = m.RequireNumber("dynamic_friction", 0.0, kMaxFriction);
  m.Finish();
  return out;
}

}  // namespace

Scene LoadScene(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);

  Scene scene;
  scene.file = file;
  std::vector<YamlMap> objects = root.MapList("objects");
  if (objects.empty()) root.Fail("objects", "a list of at least one object");
  std::set<std::string> names;
  for (size_t i = 0; i < objects.size(); ++i) {
    YamlMap& o = objects[i];
    SceneObject obj;
    obj.name = o.RequireString("name");
    if (!names.insert(obj.name).second) o.Fail("name", "a name no other object has");
    const std::string type = o.RequireString("type");
    if (type != "static" && type != "dynamic") o.Fail("type", "static or dynamic");
    obj.dynamic = type == "dynamic";
    obj.position = ToVector(o.Vec3("position", {0.0, 0.0, 0.0}, -kMaxCoordinate, kMaxCoordinate));
    obj.rotation = ReadRotation(o);

    const bool has_mass = o.Has("mass");
    const bool has_density = o.Has("density");
    if (!obj.dynamic && (has_mass || has_density)) {
      o.Fail(has_mass ? "mass" : "density",
             "neither mass nor density on a static object (it does not move)");
    }
    if (obj.dynamic) {
      if (has_mass && has_density) o.Fail("density", "either 'mass' or 'density', not both");
      if (!has_mass && !has_density)
        o.Fail("mass", "a mass in kg (or a density in kg/m³) for a dynamic object");
      if (has_mass) obj.mass = o.RequireNumber("mass", kMinMass, kMaxMass);
      if (has_density) obj.density = o.RequireNumber("density", kMinDensity, kMaxDensity);
    }
    obj.material = ReadMaterial(o);

    std::vector<YamlMap> shapes = o.MapList("shapes");
    if (shapes.empty()) o.Fail("shapes", "a list of at least one shape");
    for (YamlMap& shape : shapes) obj.shapes.push_back(ReadShape(shape, obj.dynamic));
    if (obj.dynamic) {
      const std::string problem = CheckMassProperties(obj);
      if (!problem.empty()) o.Fail("shapes", problem);
    }
    o.Finish();
    scene.objects.push_back(std::move(obj));
  }
  root.Finish();
  return scene;
}

Scene LoadSceneFile(const std::filesystem::path& file) {
  return file.extension() == ".xml" ? ImportMhapticXml(file) : LoadScene(file);
}

// ---- placement and bounds ------------------------------------------------------

bool ScenePlacement::IsIdentity() const { return position.isZero(0.0) && rotation.isIdentity(0.0); }

void ScenePlacement::ValidateOrThrow() const {
  config_check::Vec3("position", {position.x(), position.y(), position.z()}, -100.0, 100.0);
  const bool proper = rotation.allFinite() && (rotation * rotation.transpose()).isIdentity(1e-9) &&
                      std::abs(rotation.determinant() - 1.0) < 1e-9;
  if (!proper) {
    config_check::Fail("rotation", "a proper rotation (orthonormal, determinant 1)");
  }
}

Matrix3d RotationFromRpyDeg(const Vector3d& rpy_deg) {
  const Vector3d rad = rpy_deg * (std::numbers::pi / 180.0);
  return (Eigen::AngleAxisd(rad.z(), Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rad.y(), Vector3d::UnitY()) *
          Eigen::AngleAxisd(rad.x(), Vector3d::UnitX()))
      .toRotationMatrix();
}

Scene PlaceScene(Scene scene, const ScenePlacement& placement) {
  for (SceneObject& o : scene.objects) {
    o.position = placement.position + placement.rotation * o.position;
    o.rotation = placement.rotation * o.rotation;
  }
  return scene;
}

std::optional<Aabb> ShapeBounds(const SceneObject& object, const SceneShape& shape) {
  const Matrix3d rotation = object.rotation * shape.rotation;  // shape → world
  const Vector3d centre = object.position + object.rotation * shape.position;
  Vector3d half = Vector3d::Zero();
  switch (shape.kind) {
    case ShapeKind::kPlane:
      return std::nullopt;
    case ShapeKind::kBox:
      half = rotation.cwiseAbs() * shape.half_extents;
      break;
    case ShapeKind::kSphere:
      half = Vector3d::Constant(shape.radius);
      break;
    case ShapeKind::kCapsule:  // the segment between the hemisphere centres, grown by the radius
      half = (rotation.col(2) * (0.5 * shape.length)).cwiseAbs() + Vector3d::Constant(shape.radius);
      break;
    case ShapeKind::kConvex: {
      if (shape.points.empty()) return std::nullopt;
      constexpr double kInf = std::numeric_limits<double>::infinity();
      Aabb box{Vector3d::Constant(kInf), Vector3d::Constant(-kInf)};
      for (const Vector3d& p : shape.points) {
        const Vector3d w = centre + rotation * p;
        box.min = box.min.cwiseMin(w);
        box.max = box.max.cwiseMax(w);
      }
      return box;
    }
  }
  return Aabb{centre - half, centre + half};
}

std::optional<Aabb> SceneBounds(const Scene& scene) {
  std::optional<Aabb> out;
  for (const SceneObject& o : scene.objects) {
    for (const SceneShape& s : o.shapes) {
      const auto box = ShapeBounds(o, s);
      if (!box) continue;
      if (!out) {
        out = box;
      } else {
        out->min = out->min.cwiseMin(box->min);
        out->max = out->max.cwiseMax(box->max);
      }
    }
  }
  return out;
}

}  // namespace haptel
