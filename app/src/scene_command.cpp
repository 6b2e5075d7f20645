#include "haptel/app/scene_command.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/core/args.hpp"
#include "haptel/core/json.hpp"
#include "haptel/geometry/mass_properties.hpp"

namespace haptel::app {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr const char* kUsage =
    "usage: haptel scene FILE [--json] [--config RUN.yaml]\n"
    "  Loads a haptic scene (YAML, or the thesis's MHaptic .xml) and prints its objects,\n"
    "  their shapes, the total mass and the bounding box, in the device frame\n"
    "  (x forward, y left, z up; m, kg). Exit 0, or 2 with one line saying what is wrong.\n"
    "  --config RUN.yaml  apply that run configuration's scene_placement first\n"
    "  --json             one JSON line instead of the text\n";

// "[a, b, c]" (text) or "[a,b,c]" (JSON). Built by appending: GCC 12 warns
// falsely (-Wrestrict) on "[" + std::string.
std::string List(const double* values, int count, const char* separator) {
  std::string out = "[";
  for (int i = 0; i < count; ++i) {
    if (i > 0) out += separator;
    out += JsonNumber(values[i] + 0.0);  // (+ 0.0: no "-0")
  }
  out += ']';
  return out;
}

std::string Vec(const Vector3d& v) { return List(v.data(), 3, ", "); }
std::string JsonVec(const Vector3d& v) { return List(v.data(), 3, ","); }
std::string JsonMatrix(const Matrix3d& m) {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> rows = m;  // row by row
  return List(rows.data(), 9, ",");
}

// Roll, pitch, yaw in degrees (the inverse of RotationFromRpyDeg).
Vector3d RpyDeg(const Matrix3d& r) {
  const double deg = 180.0 / std::numbers::pi;
  return Vector3d(std::atan2(r(2, 1), r(2, 2)), std::asin(std::clamp(-r(2, 0), -1.0, 1.0)),
                  std::atan2(r(1, 0), r(0, 0))) *
         deg;
}

bool Identity(const Matrix3d& r) { return (r - Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9; }

std::string Pose(const Vector3d& p, const Matrix3d& r) {
  std::string out = "at " + Vec(p);
  if (!Identity(r)) out += ", rpy_deg " + Vec(RpyDeg(r));
  return out;
}

std::string ShapeText(const SceneShape& s) {
  switch (s.kind) {
    case ShapeKind::kBox:
      return "box, half sides " + Vec(s.half_extents);
    case ShapeKind::kSphere:
      return "sphere, radius " + JsonNumber(s.radius);
    case ShapeKind::kCapsule:
      return "capsule, radius " + JsonNumber(s.radius) + ", length " + JsonNumber(s.length) +
             " (between the hemisphere centres, along its z)";
    case ShapeKind::kPlane:
      return "plane, normal " + Vec(s.normal) + ", offset " + JsonNumber(s.offset);
    case ShapeKind::kConvex:
      return "convex hull of " + std::to_string(s.points.size()) + " points";
  }
  return "?";
}

std::string ShapeJson(const SceneShape& s, double mass_kg) {
  std::string out = "{\"type\":" + JsonString(ShapeKindName(s.kind)) +
                    ",\"position\":" + JsonVec(s.position) +
                    ",\"rotation\":" + JsonMatrix(s.rotation);
  switch (s.kind) {
    case ShapeKind::kBox:
      out += ",\"half_extents\":" + JsonVec(s.half_extents);
      break;
    case ShapeKind::kSphere:
      out += ",\"radius\":" + JsonNumber(s.radius);
      break;
    case ShapeKind::kCapsule:
      out += ",\"radius\":" + JsonNumber(s.radius) + ",\"length\":" + JsonNumber(s.length);
      break;
    case ShapeKind::kPlane:
      out += ",\"normal\":" + JsonVec(s.normal) + ",\"offset\":" + JsonNumber(s.offset);
      break;
    case ShapeKind::kConvex: {
      out += ",\"points\":[";
      for (size_t i = 0; i < s.points.size(); ++i) {
        if (i > 0) out += ',';
        out += JsonVec(s.points[i]);
      }
      out += "]";
      break;
    }
  }
  return out + ",\"mass_kg\":" + JsonNumber(mass_kg) + "}";
}

void Report(const Scene& scene, const std::optional<ScenePlacement>& placement, bool json,
            std::ostream& out) {
  size_t dynamic = 0;
  double total_mass = 0.0;
  std::vector<std::vector<double>> masses;  // per object, per shape (dynamic objects)
  for (const SceneObject& o : scene.objects) {
    masses.push_back(o.dynamic ? ShapeMasses(o) : std::vector<double>(o.shapes.size(), 0.0));
    if (o.dynamic) ++dynamic;
    for (double m : masses.back()) total_mass += m;
  }
  const auto bounds = SceneBounds(scene);

  if (json) {
    std::string line = "{\"file\":" + JsonString(scene.file.string()) + ",\"frame\":\"device\"";
    line += ",\"placement\":";
    line += placement ? "{\"position\":" + JsonVec(placement->position) +
                            ",\"rotation\":" + JsonMatrix(placement->rotation) + "}"
                      : std::string("null");
    line += ",\"objects\":[";
    for (size_t i = 0; i < scene.objects.size(); ++i) {
      const SceneObject& o = scene.objects[i];
      double mass = 0.0;
      for (double m : masses[i]) mass += m;
      line += (i == 0 ? "{" : ",{") + std::string("\"name\":") + JsonString(o.name) +
              ",\"dynamic\":" + (o.dynamic ? "true" : "false") +
              ",\"position\":" + JsonVec(o.position) + ",\"rotation\":" + JsonMatrix(o.rotation) +
              ",\"mass_kg\":" + JsonNumber(mass) +
              ",\"material\":{\"restitution\":" + JsonNumber(o.material.restitution) +
              ",\"static_friction\":" + JsonNumber(o.material.static_friction) +
              ",\"dynamic_friction\":" + JsonNumber(o.material.dynamic_friction) + "},\"shapes\":[";
      for (size_t j = 0; j < o.shapes.size(); ++j) {
        if (j > 0) line += ',';
        line += ShapeJson(o.shapes[j], masses[i][j]);
      }
      line += "]}";
    }
    line += "],\"objects_dynamic\":" + std::to_string(dynamic) +
            ",\"objects_static\":" + std::to_string(scene.objects.size() - dynamic) +
            ",\"total_mass_kg\":" + JsonNumber(total_mass) + ",\"bounds\":" +
            (bounds ? "{\"min\":" + JsonVec(bounds->min) + ",\"max\":" + JsonVec(bounds->max) + "}"
                    : std::string("null")) +
            "}";
    out << line << "\n";
    return;
  }

  out << "scene " << scene.file.string() << ": " << scene.objects.size()
      << (scene.objects.size() == 1 ? " object" : " objects") << " (" << dynamic << " dynamic, "
      << scene.objects.size() - dynamic << " static)\n";
  out << "device frame: x forward, y left, z up; m, kg";
  if (placement) out << "; placed " << Pose(placement->position, placement->rotation);
  out << "\n";
  for (size_t i = 0; i < scene.objects.size(); ++i) {
    const SceneObject& o = scene.objects[i];
    out << "\n"
        << o.name << "  " << (o.dynamic ? "dynamic" : "static") << "  "
        << Pose(o.position, o.rotation);
    if (o.dynamic) {
      double mass = 0.0;
      for (double m : masses[i]) mass += m;
      out << "  mass " << JsonNumber(mass);
    }
    out << "\n";
    for (size_t j = 0; j < o.shapes.size(); ++j) {
      const SceneShape& s = o.shapes[j];
      out << "  " << ShapeText(s) << "; " << Pose(s.position, s.rotation) << " in the object";
      if (o.dynamic) out << "; mass " << JsonNumber(masses[i][j]);
      out << "\n";
    }
    out << "  material: restitution " << JsonNumber(o.material.restitution) << ", static friction "
        << JsonNumber(o.material.static_friction) << ", dynamic friction "
        << JsonNumber(o.material.dynamic_friction) << "\n";
  }
  out << "\ntotal mass (dynamic objects): " << JsonNumber(total_mass) << " kg\n";
  if (bounds) {
    out << "bounding box: min " << Vec(bounds->min) << ", max " << Vec(bounds->max)
        << " (planes, unbounded, left out)\n";
  } else {
    out << "bounding box: none (only planes, which are unbounded)\n";
  }
}

}  // namespace

int SceneCommand(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  std::string file;
  try {
    const Args args(argc, argv, {"config"}, {"json", "help"});
    if (args.Flag("help")) {
      out << kUsage;
      return 0;
    }
    if (args.positional().size() != 1) {
      throw UsageError(args.positional().empty() ? "missing the scene FILE"
                                                 : "expected one scene FILE, got " +
                                                       std::to_string(args.positional().size()));
    }
    file = args.positional()[0];
    std::optional<ScenePlacement> placement;
    if (const auto config = args.Value("config")) placement = LoadRun(*config).scene_placement;
    Scene scene = LoadSceneFile(file);
    if (placement) scene = PlaceScene(std::move(scene), *placement);
    Report(scene, placement, args.Flag("json"), out);
    return 0;
  } catch (const UsageError& e) {
    err << "haptel scene: " << e.what() << " (see haptel scene --help)\n";
  } catch (const ConfigError& e) {
    err << "haptel: " << e.what() << "\n";
  } catch (const std::exception& e) {  // anything else reading the scene is still bad input
    err << "haptel: " << file << ": " << e.what() << "\n";
  }
  return 2;
}

}  // namespace haptel::app
