#include "haptel/geometry/mass_properties.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>

namespace haptel {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kPi = std::numbers::pi;

// Mass properties per unit density, in the shape's own frame.
MassProperties Box(const Vector3d& h) {
  MassProperties p;
  p.volume = 8.0 * h.x() * h.y() * h.z();
  p.mass = p.volume;
  const Vector3d sq = h.cwiseProduct(h);
  p.inertia =
      (p.mass / 3.0 * Vector3d(sq.y() + sq.z(), sq.x() + sq.z(), sq.x() + sq.y())).asDiagonal();
  return p;
}

MassProperties Sphere(double r) {
  MassProperties p;
  p.volume = 4.0 / 3.0 * kPi * r * r * r;
  p.mass = p.volume;
  p.inertia = Matrix3d::Identity() * (0.4 * p.mass * r * r);
  return p;
}

// A cylinder of length h along z between two hemispheres of radius r. Each
// hemisphere (mass mh) about its own flat-face diameter has 2/5·mh·r²; its
// centre of mass lies 3r/8 from the flat face, i.e. h/2 + 3r/8 from the
// capsule's centre, which gives mh·(2/5 r² + h²/4 + 3hr/8) about the capsule's
// transverse axes.
MassProperties Capsule(double r, double h) {
  const double mc = kPi * r * r * h;
  const double mh = 2.0 / 3.0 * kPi * r * r * r;
  MassProperties p;
  p.volume = mc + 2.0 * mh;
  p.mass = p.volume;
  const double axial = mc * r * r / 2.0 + 2.0 * (0.4 * mh * r * r);
  const double transverse = mc * (r * r / 4.0 + h * h / 12.0) +
                            2.0 * mh * (0.4 * r * r + h * h / 4.0 + 3.0 * h * r / 8.0);
  p.inertia = Vector3d(transverse, transverse, axial).asDiagonal();
  return p;
}

// Sum of tetrahedra (interior point, face triangle) of the hull. The second
// moment of a tetrahedron with vertices v0..v3 is ∫x xᵀ dV =
// V/20 · (Σ vᵢvᵢᵀ + s sᵀ), s = Σ vᵢ (vertices relative to any origin).
MassProperties Convex(const std::vector<Vector3d>& points) {
  const ConvexHull hull = ComputeConvexHull(points);
  Vector3d origin = Vector3d::Zero();
  for (const Vector3d& q : points) origin += q;
  origin /= static_cast<double>(points.size());  // inside the hull (a mean of points)
  double volume = 0.0;
  Vector3d first = Vector3d::Zero();
  Matrix3d second = Matrix3d::Zero();
  for (const auto& t : hull.triangles) {
    const Vector3d a = points[t[0]] - origin;
    const Vector3d b = points[t[1]] - origin;
    const Vector3d c = points[t[2]] - origin;
    const double v = a.dot(b.cross(c)) / 6.0;
    const Vector3d s = a + b + c;
    volume += v;
    first += v * s / 4.0;
    second +=
        v / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  if (!(volume > 0.0)) throw std::invalid_argument("convex shape: the points span no volume");
  MassProperties p;
  p.volume = volume;
  p.mass = volume;
  const Vector3d centre = first / volume;
  const Matrix3d about_com = second - volume * centre * centre.transpose();
  p.com = origin + centre;
  p.inertia = Matrix3d::Identity() * about_com.trace() - about_com;
  return p;
}

void CheckFinitePositive(double value, const char* what) {
  if (!std::isfinite(value) || value <= 0.0) {
    throw std::invalid_argument(std::string(what) + " must be a finite positive number");
  }
}

// ---- convex hull ----------------------------------------------------------

struct Face {
  std::array<int, 3> v;
  Vector3d normal;  // unit, outward
  double d;         // normal·x = d on the face
  double Distance(const Vector3d& p) const { return normal.dot(p) - d; }
};

Face MakeFace(const std::vector<Vector3d>& pts, int a, int b, int c, const Vector3d& fallback) {
  Vector3d n = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
  const double len = n.norm();
  // A sliver (the new point in line with a horizon edge) keeps the normal of
  // the face it replaces, so later visibility tests stay meaningful.
  n = len > 0.0 ? Vector3d(n / len) : fallback;
  return Face{{a, b, c}, n, n.dot(pts[a])};
}

}  // namespace

ConvexHull ComputeConvexHull(const std::vector<Vector3d>& pts) {
  const int n = static_cast<int>(pts.size());
  if (n < 4) throw std::invalid_argument("convex shape: needs at least 4 points");
  Vector3d lo = pts[0];
  Vector3d hi = pts[0];
  for (const Vector3d& p : pts) {
    if (!p.allFinite()) throw std::invalid_argument("convex shape: a point is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double scale = (hi - lo).norm();
  const double eps = 1e-9 * scale;         // "on the plane" for visibility
  const double degenerate = 1e-7 * scale;  // initial simplex must be thicker than this
  const std::invalid_argument flat(
      "convex shape: the points span no volume (all on a line or a plane)");
  if (!(scale > 0.0)) throw flat;

  // Initial tetrahedron: an extreme point, the farthest from it, the farthest
  // from their line, the farthest from their plane.
  int i0 = 0;
  for (int i = 1; i < n; ++i) {
    if (pts[i].x() < pts[i0].x()) i0 = i;
  }
  int i1 = i0;
  for (int i = 0; i < n; ++i) {
    if ((pts[i] - pts[i0]).norm() > (pts[i1] - pts[i0]).norm()) i1 = i;
  }
  if ((pts[i1] - pts[i0]).norm() <= degenerate) throw flat;
  const Vector3d axis = (pts[i1] - pts[i0]).normalized();
  int i2 = i0;
  double best = 0.0;
  for (int i = 0; i < n; ++i) {
    const double dist = (pts[i] - pts[i0]).cross(axis).norm();
    if (dist > best) {
      best = dist;
      i2 = i;
    }
  }
  if (best <= degenerate) throw flat;
  const Vector3d plane_n = (pts[i1] - pts[i0]).cross(pts[i2] - pts[i0]).normalized();
  int i3 = i0;
  best = 0.0;
  for (int i = 0; i < n; ++i) {
    const double dist = std::abs(plane_n.dot(pts[i] - pts[i0]));
    if (dist > best) {
      best = dist;
      i3 = i;
    }
  }
  if (best <= degenerate) throw flat;

  const Vector3d inside = (pts[i0] + pts[i1] + pts[i2] + pts[i3]) / 4.0;
  std::vector<Face> faces;
  const std::array<std::array<int, 3>, 4> tet{
      {{i0, i1, i2}, {i0, i3, i1}, {i1, i3, i2}, {i2, i3, i0}}};
  for (auto f : tet) {
    Face face = MakeFace(pts, f[0], f[1], f[2], Vector3d::UnitZ());
    if (face.Distance(inside) > 0.0) face = MakeFace(pts, f[0], f[2], f[1], Vector3d::UnitZ());
    faces.push_back(face);
  }

  for (int p = 0; p < n; ++p) {
    if (p == i0 || p == i1 || p == i2 || p == i3) continue;
    std::vector<bool> visible(faces.size(), false);
    bool any = false;
    for (size_t f = 0; f < faces.size(); ++f) {
      visible[f] = faces[f].Distance(pts[p]) > eps;
      any = any || visible[f];
    }
    if (!any) continue;  // inside or on the hull
    // Directed edges of the visible faces; the horizon is those whose reverse
    // belongs to no visible face. Each maps to the normal of its face.
    std::map<std::pair<int, int>, Vector3d> edges;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (!visible[f]) continue;
      const auto& v = faces[f].v;
      for (int k = 0; k < 3; ++k) edges[{v[k], v[(k + 1) % 3]}] = faces[f].normal;
    }
    std::vector<Face> next;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (!visible[f]) next.push_back(faces[f]);
    }
    for (const auto& [edge, normal] : edges) {
      if (edges.count({edge.second, edge.first}) == 0) {
        next.push_back(MakeFace(pts, edge.first, edge.second, p, normal));
      }
    }
    faces = std::move(next);
  }

  // A closed, consistently oriented surface: every directed edge once, and
  // its reverse once.
  std::map<std::pair<int, int>, int> count;
  for (const Face& f : faces) {
    for (int k = 0; k < 3; ++k) ++count[{f.v[k], f.v[(k + 1) % 3]}];
  }
  for (const auto& [edge, c] : count) {
    const auto reverse = count.find({edge.second, edge.first});
    if (c != 1 || reverse == count.end() || reverse->second != 1) {
      throw std::invalid_argument(
          "convex shape: the hull of these points is numerically degenerate");
    }
  }
  ConvexHull hull;
  for (const Face& f : faces) hull.triangles.push_back(f.v);
  return hull;
}

Matrix3d ShiftInertia(const Matrix3d& inertia_about_com, double mass, const Vector3d& offset) {
  return inertia_about_com +
         mass * (offset.squaredNorm() * Matrix3d::Identity() - offset * offset.transpose());
}

MassProperties ShapeMassProperties(const SceneShape& shape, double density) {
  CheckFinitePositive(density, "density");
  MassProperties local;
  switch (shape.kind) {
    case ShapeKind::kBox:
      CheckFinitePositive(shape.half_extents.minCoeff(), "box half extents");
      local = Box(shape.half_extents);
      break;
    case ShapeKind::kSphere:
      CheckFinitePositive(shape.radius, "sphere radius");
      local = Sphere(shape.radius);
      break;
    case ShapeKind::kCapsule:
      CheckFinitePositive(shape.radius, "capsule radius");
      if (!std::isfinite(shape.length) || shape.length < 0.0) {
        throw std::invalid_argument("capsule length must be finite and >= 0");
      }
      local = Capsule(shape.radius, shape.length);
      break;
    case ShapeKind::kPlane:
      throw std::invalid_argument("a plane has no finite volume (planes belong on static objects)");
    case ShapeKind::kConvex:
      local = Convex(shape.points);
      break;
  }
  MassProperties p;
  p.volume = local.volume;
  p.mass = local.mass * density;
  p.com = shape.position + shape.rotation * local.com;
  p.inertia = density * shape.rotation * local.inertia * shape.rotation.transpose();
  return p;
}

MassProperties CombineMassProperties(const std::vector<MassProperties>& parts) {
  MassProperties total;
  for (const MassProperties& part : parts) {
    total.mass += part.mass;
    total.volume += part.volume;
    total.com += part.mass * part.com;
  }
  if (!(total.mass > 0.0)) throw std::invalid_argument("no mass: nothing to combine");
  total.com /= total.mass;
  for (const MassProperties& part : parts) {
    total.inertia += ShiftInertia(part.inertia, part.mass, part.com - total.com);
  }
  return total;
}

MassProperties ComputeMassProperties(const std::vector<SceneShape>& shapes, double density) {
  std::vector<MassProperties> parts;
  parts.reserve(shapes.size());
  for (const SceneShape& shape : shapes) parts.push_back(ShapeMassProperties(shape, density));
  if (parts.empty()) throw std::invalid_argument("no shapes");
  return CombineMassProperties(parts);
}

namespace {

// Each shape's mass properties at its own density when it has one, else the
// object's (else a uniform 1: only the ratios matter before the scaling to the
// object's mass), and the factor that scales them to the object's mass.
std::pair<std::vector<MassProperties>, double> ShapeParts(const SceneObject& object) {
  if (!object.dynamic) throw std::invalid_argument("a static object has no mass properties");
  if (object.density <= 0.0) CheckFinitePositive(object.mass, "mass (or density)");
  const double uniform = object.density > 0.0 ? object.density : 1.0;
  std::vector<MassProperties> parts;
  parts.reserve(object.shapes.size());
  double total = 0.0;
  for (const SceneShape& shape : object.shapes) {
    if (shape.density != 0.0) CheckFinitePositive(shape.density, "shape density");
    parts.push_back(ShapeMassProperties(shape, shape.density > 0.0 ? shape.density : uniform));
    total += parts.back().mass;
  }
  if (parts.empty()) throw std::invalid_argument("no shapes");
  return {std::move(parts), object.density > 0.0 ? 1.0 : object.mass / total};
}

}  // namespace

MassProperties ComputeMassProperties(const SceneObject& object) {
  const auto [parts, scale] = ShapeParts(object);
  MassProperties p = CombineMassProperties(parts);
  p.mass *= scale;
  p.inertia *= scale;
  return p;
}

std::vector<double> ShapeMasses(const SceneObject& object) {
  const auto [parts, scale] = ShapeParts(object);
  std::vector<double> out;
  for (const MassProperties& part : parts) out.push_back(part.mass * scale);
  return out;
}

PrincipalInertia Diagonalize(const Matrix3d& inertia) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> solver(0.5 * (inertia + inertia.transpose()));
  PrincipalInertia out;
  out.moments = solver.eigenvalues();
  out.axes = solver.eigenvectors();
  if (out.axes.determinant() < 0.0) out.axes.col(2) = -out.axes.col(2);
  return out;
}

}  // namespace haptel
