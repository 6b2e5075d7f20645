// Mass, centre of mass and inertia from scene shapes, against closed forms and
// independent numerical integration.
#include <Eigen/Geometry>
#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>

#include "haptel/geometry/mass_properties.hpp"

using Eigen::Matrix3d;
using Eigen::Vector3d;
using haptel::ComputeConvexHull;
using haptel::ComputeMassProperties;
using haptel::MassProperties;
using haptel::SceneShape;
using haptel::ShapeKind;
using haptel::ShapeMassProperties;

namespace {

constexpr double kPi = std::numbers::pi;

SceneShape Box(Vector3d half, Vector3d position = Vector3d::Zero(),
               Matrix3d rotation = Matrix3d::Identity()) {
  SceneShape s;
  s.kind = ShapeKind::kBox;
  s.half_extents = half;
  s.position = position;
  s.rotation = rotation;
  return s;
}

SceneShape Sphere(double r, Vector3d position = Vector3d::Zero()) {
  SceneShape s;
  s.kind = ShapeKind::kSphere;
  s.radius = r;
  s.position = position;
  return s;
}

SceneShape Capsule(double r, double length) {
  SceneShape s;
  s.kind = ShapeKind::kCapsule;
  s.radius = r;
  s.length = length;
  return s;
}

SceneShape Convex(std::vector<Vector3d> points) {
  SceneShape s;
  s.kind = ShapeKind::kConvex;
  s.points = std::move(points);
  return s;
}

std::vector<Vector3d> CubeCorners(const Vector3d& half, const Vector3d& centre) {
  std::vector<Vector3d> out;
  for (int i = 0; i < 8; ++i) {
    out.push_back(centre + Vector3d((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                    (i & 4) ? half.z() : -half.z()));
  }
  return out;
}

void RequireMatrixNear(const Matrix3d& a, const Matrix3d& b, double tol) {
  INFO("got\n" << a << "\nexpected\n" << b);
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

void RequireVectorNear(const Vector3d& a, const Vector3d& b, double tol) {
  INFO("got " << a.transpose() << ", expected " << b.transpose());
  REQUIRE((a - b).cwiseAbs().maxCoeff() <= tol);
}

// A solid of revolution about z with radius profile rho(z) on [z0, z1],
// integrated by slices (midpoint rule): an independent check of the closed forms.
template <typename Profile>
MassProperties Revolve(Profile rho, double z0, double z1, double density, int slices = 200000) {
  MassProperties p;
  double mz = 0.0;
  double izz = 0.0;
  double ixx = 0.0;
  const double dz = (z1 - z0) / slices;
  for (int i = 0; i < slices; ++i) {
    const double z = z0 + (i + 0.5) * dz;
    const double r = rho(z);
    const double dm = density * kPi * r * r * dz;
    p.mass += dm;
    mz += dm * z;
    izz += dm * r * r / 2.0;
    ixx += dm * (r * r / 4.0 + z * z);
  }
  p.com = Vector3d(0, 0, mz / p.mass);
  const double zc = mz / p.mass;
  p.inertia = Vector3d(ixx - p.mass * zc * zc, ixx - p.mass * zc * zc, izz).asDiagonal();
  return p;
}

}  // namespace

TEST_CASE("box: mass and inertia are the closed forms", "[mass]") {
  const Vector3d h(0.1, 0.2, 0.3);
  const MassProperties p = ShapeMassProperties(Box(h), 1000.0);
  const double m = 1000.0 * 0.2 * 0.4 * 0.6;
  REQUIRE(p.mass == Approx(m));
  REQUIRE(p.volume == Approx(0.048));
  RequireVectorNear(p.com, Vector3d::Zero(), 1e-15);
  // m/12 (b² + c²) with full edge lengths b, c.
  const Matrix3d expected =
      Vector3d(m / 12 * (0.16 + 0.36), m / 12 * (0.04 + 0.36), m / 12 * (0.04 + 0.16)).asDiagonal();
  RequireMatrixNear(p.inertia, expected, 1e-12);
}

TEST_CASE("sphere: 2/5 m r²", "[mass]") {
  const MassProperties p = ShapeMassProperties(Sphere(0.1), 500.0);
  const double m = 500.0 * 4.0 / 3.0 * kPi * 1e-3;
  REQUIRE(p.mass == Approx(m));
  RequireMatrixNear(p.inertia, Matrix3d::Identity() * 0.4 * m * 0.01, 1e-14);
  const MassProperties slices =
      Revolve([](double z) { return std::sqrt(std::max(0.0, 0.01 - z * z)); }, -0.1, 0.1, 500.0);
  REQUIRE(p.mass == Approx(slices.mass).epsilon(1e-6));
  RequireMatrixNear(p.inertia, slices.inertia, 1e-6 * p.inertia.maxCoeff());
}

TEST_CASE("capsule: cylinder plus two hemispheres, along local z", "[mass]") {
  const double r = 0.05;
  const double h = 0.2;
  const double density = 800.0;
  const MassProperties p = ShapeMassProperties(Capsule(r, h), density);
  const double volume = kPi * r * r * h + 4.0 / 3.0 * kPi * r * r * r;
  REQUIRE(p.volume == Approx(volume));
  REQUIRE(p.mass == Approx(density * volume));
  RequireVectorNear(p.com, Vector3d::Zero(), 1e-15);

  // Independent: slice the solid of revolution.
  const auto profile = [&](double z) {
    const double a = std::abs(z);
    if (a <= h / 2) return r;
    const double u = a - h / 2;
    return std::sqrt(std::max(0.0, r * r - u * u));
  };
  const MassProperties slices = Revolve(profile, -h / 2 - r, h / 2 + r, density);
  REQUIRE(p.mass == Approx(slices.mass).epsilon(1e-6));
  RequireMatrixNear(p.inertia, slices.inertia, 1e-6 * p.inertia.maxCoeff());
  REQUIRE(p.inertia(2, 2) < p.inertia(0, 0));  // slender about its axis

  // Length 0 is a sphere.
  const MassProperties ball = ShapeMassProperties(Capsule(r, 0.0), density);
  const MassProperties sphere = ShapeMassProperties(Sphere(r), density);
  REQUIRE(ball.mass == Approx(sphere.mass));
  RequireMatrixNear(ball.inertia, sphere.inertia, 1e-15);
}

TEST_CASE("offset and rotated shapes: parallel-axis theorem and rotation", "[mass]") {
  const double r = 0.1;
  const double d = 0.3;
  SECTION("two spheres either side of the origin") {
    const MassProperties p = ComputeMassProperties(
        {Sphere(r, Vector3d(d, 0, 0)), Sphere(r, Vector3d(-d, 0, 0))}, 1000.0);
    const double m = 1000.0 * 4.0 / 3.0 * kPi * r * r * r;
    REQUIRE(p.mass == Approx(2 * m));
    RequireVectorNear(p.com, Vector3d::Zero(), 1e-15);
    const double own = 0.4 * m * r * r;
    RequireMatrixNear(p.inertia,
                      Vector3d(2 * own, 2 * (own + m * d * d), 2 * (own + m * d * d)).asDiagonal(),
                      1e-12);
  }
  SECTION("one offset box keeps its inertia about its own centre") {
    const Vector3d h(0.1, 0.2, 0.3);
    const MassProperties at_origin = ShapeMassProperties(Box(h), 700.0);
    const MassProperties moved = ComputeMassProperties({Box(h, Vector3d(1, 2, 3))}, 700.0);
    RequireVectorNear(moved.com, Vector3d(1, 2, 3), 1e-12);
    RequireMatrixNear(moved.inertia, at_origin.inertia, 1e-12);
  }
  SECTION("uneven pair: com and off-diagonal terms") {
    // A 1 kg point-like sphere at (1, 1, 0) and another at the origin, 3 kg:
    // com at (0.25, 0.25, 0); the product of inertia Ixy = -Σ m x y.
    const double small = 1e-3;
    const double rho1 = 1.0 / (4.0 / 3.0 * kPi * small * small * small);
    MassProperties a = ShapeMassProperties(Sphere(small, Vector3d(1, 1, 0)), rho1);
    MassProperties b = ShapeMassProperties(Sphere(small), 3 * rho1);
    const MassProperties p = haptel::CombineMassProperties({a, b});
    REQUIRE(p.mass == Approx(4.0));
    RequireVectorNear(p.com, Vector3d(0.25, 0.25, 0), 1e-12);
    const double ixy = -(1.0 * 0.75 * 0.75 + 3.0 * 0.25 * 0.25);
    REQUIRE(p.inertia(0, 1) == Approx(ixy).epsilon(1e-5));
    REQUIRE(p.inertia(2, 2) == Approx(1.0 * 2 * 0.75 * 0.75 + 3.0 * 2 * 0.25 * 0.25).epsilon(1e-5));
  }
  SECTION("a box turned 90° about z swaps its x and y moments") {
    const Matrix3d turn = Eigen::AngleAxisd(kPi / 2, Vector3d::UnitZ()).toRotationMatrix();
    const MassProperties turned =
        ShapeMassProperties(Box(Vector3d(0.1, 0.2, 0.3), Vector3d::Zero(), turn), 1.0);
    const MassProperties swapped = ShapeMassProperties(Box(Vector3d(0.2, 0.1, 0.3)), 1.0);
    RequireMatrixNear(turned.inertia, swapped.inertia, 1e-15);
  }
  SECTION("a box turned about a general axis: same principal moments, rotated axes") {
    const Matrix3d turn = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const MassProperties plain = ShapeMassProperties(Box(Vector3d(0.1, 0.2, 0.3)), 1.0);
    const MassProperties turned =
        ShapeMassProperties(Box(Vector3d(0.1, 0.2, 0.3), Vector3d::Zero(), turn), 1.0);
    REQUIRE(std::abs(turned.inertia(0, 1)) > 1e-6);
    const auto principal = haptel::Diagonalize(turned.inertia);
    RequireVectorNear(principal.moments,
                      Vector3d(plain.inertia(2, 2), plain.inertia(1, 1), plain.inertia(0, 0)),
                      1e-15);
    REQUIRE(principal.axes.determinant() == Approx(1.0));
    RequireMatrixNear(principal.axes * principal.moments.asDiagonal() * principal.axes.transpose(),
                      turned.inertia, 1e-15);
  }
  SECTION("ShiftInertia is the parallel-axis theorem") {
    const Matrix3d shifted = haptel::ShiftInertia(Matrix3d::Zero(), 2.0, Vector3d(0, 0, 3));
    RequireMatrixNear(shifted, Vector3d(18, 18, 0).asDiagonal(), 1e-15);
  }
}

TEST_CASE("convex hull of a cube's 8 corners is the box", "[mass][hull]") {
  const Vector3d h(0.1, 0.2, 0.3);
  const Vector3d centre(0.5, -0.25, 1.0);
  const MassProperties box = ShapeMassProperties(Box(h, centre), 900.0);
  std::vector<Vector3d> corners = CubeCorners(h, centre);
  SECTION("corners only") {
    const auto hull = ComputeConvexHull(corners);
    REQUIRE(hull.triangles.size() == 12);
  }
  SECTION("with interior, face and edge points, shuffled") {
    corners.push_back(centre);
    corners.push_back(centre + Vector3d(h.x(), 0, 0));        // face centre
    corners.push_back(centre + Vector3d(h.x(), h.y(), 0));    // edge midpoint
    corners.push_back(centre + Vector3d(0.01, -0.02, 0.03));  // interior
    std::mt19937 rng(7);
    std::shuffle(corners.begin(), corners.end(), rng);
  }
  const MassProperties hull = ShapeMassProperties(Convex(corners), 900.0);
  REQUIRE(hull.volume == Approx(box.volume));
  REQUIRE(hull.mass == Approx(box.mass));
  RequireVectorNear(hull.com, centre, 1e-12);
  RequireMatrixNear(hull.inertia, box.inertia, 1e-12);
}

TEST_CASE("convex hull of a tetrahedron: closed-form volume, centroid, inertia", "[mass][hull]") {
  const double a = 0.3;
  const double density = 2000.0;
  const MassProperties p = ShapeMassProperties(
      Convex({Vector3d(0, 0, 0), Vector3d(a, 0, 0), Vector3d(0, a, 0), Vector3d(0, 0, a)}),
      density);
  const double volume = a * a * a / 6.0;
  const double m = density * volume;
  REQUIRE(p.volume == Approx(volume));
  RequireVectorNear(p.com, Vector3d::Constant(a / 4), 1e-14);
  // About the right-angle corner: ∫x² dV = a⁵/60, ∫xy dV = a⁵/120.
  const double a5 = std::pow(a, 5) * density;
  Matrix3d about_corner;
  about_corner << a5 / 30, -a5 / 120, -a5 / 120,  //
      -a5 / 120, a5 / 30, -a5 / 120,              //
      -a5 / 120, -a5 / 120, a5 / 30;
  const Matrix3d expected = haptel::ShiftInertia(about_corner, -m, Vector3d::Constant(a / 4));
  RequireMatrixNear(p.inertia, expected, 1e-12 * a5);
  REQUIRE(m == Approx(p.mass));
}

TEST_CASE("convex hull of 64 random points is closed, convex and holds them all", "[hull]") {
  std::mt19937 rng(42);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Vector3d> pts;
  for (int i = 0; i < 64; ++i) {
    Vector3d v(normal(rng), normal(rng), normal(rng));
    v = v.normalized() * (i % 4 == 0 ? 0.5 * uniform(rng) : 1.0);  // most on the unit sphere
    pts.push_back(v);
  }
  const auto hull = ComputeConvexHull(pts);
  std::set<int> vertices;
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : hull.triangles) {
    const Vector3d n = (pts[t[1]] - pts[t[0]]).cross(pts[t[2]] - pts[t[0]]).normalized();
    for (const Vector3d& p : pts) REQUIRE(n.dot(p - pts[t[0]]) <= 1e-9);
    for (int k = 0; k < 3; ++k) {
      vertices.insert(t[k]);
      ++edges[{t[k], t[(k + 1) % 3]}];
    }
  }
  for (const auto& [e, count] : edges) {
    REQUIRE(count == 1);
    REQUIRE(edges.count({e.second, e.first}) == 1);
  }
  // Euler: V − E + F = 2 for a closed triangulated surface.
  REQUIRE(static_cast<int>(vertices.size()) - static_cast<int>(edges.size() / 2) +
              static_cast<int>(hull.triangles.size()) ==
          2);
  REQUIRE(vertices.size() >= 40);  // the 48 surface points, less any hidden in a facet
  const MassProperties p = ShapeMassProperties(Convex(pts), 1.0);
  REQUIRE(p.volume < 4.0 / 3.0 * kPi);
  REQUIRE(p.volume > 0.5 * 4.0 / 3.0 * kPi);
}

TEST_CASE("bad shapes are rejected", "[mass][hull]") {
  REQUIRE_THROWS_AS(ComputeConvexHull({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)}),
                    std::invalid_argument);
  REQUIRE_THROWS_AS(ComputeConvexHull({Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0),
                                       Vector3d(1, 1, 0), Vector3d(0.5, 0.5, 0)}),
                    std::invalid_argument);  // coplanar
  REQUIRE_THROWS_AS(ComputeConvexHull({Vector3d(0, 0, 0), Vector3d(1, 1, 1), Vector3d(2, 2, 2),
                                       Vector3d(3, 3, 3)}),
                    std::invalid_argument);  // collinear
  SceneShape plane;
  plane.kind = ShapeKind::kPlane;
  REQUIRE_THROWS_AS(ShapeMassProperties(plane, 1.0), std::invalid_argument);
  REQUIRE_THROWS_AS(ShapeMassProperties(Sphere(0.1), 0.0), std::invalid_argument);
  REQUIRE_THROWS_AS(ShapeMassProperties(Sphere(0.0), 1.0), std::invalid_argument);
}

TEST_CASE("an object's mass properties: from its density, or scaled to its mass", "[mass]") {
  haptel::SceneObject object;
  object.dynamic = true;
  object.shapes = {Box(Vector3d(0.05, 0.05, 0.05)), Sphere(0.05, Vector3d(0, 0, 0.1))};
  object.density = 600.0;
  const MassProperties by_density = ComputeMassProperties(object);
  REQUIRE(by_density.mass == Approx(600.0 * (0.001 + 4.0 / 3.0 * kPi * 0.05 * 0.05 * 0.05)));

  object.density = 0.0;
  object.mass = 0.5;
  const MassProperties by_mass = ComputeMassProperties(object);
  REQUIRE(by_mass.mass == Approx(0.5));
  REQUIRE(by_mass.volume == Approx(by_density.volume));
  RequireVectorNear(by_mass.com, by_density.com, 1e-15);
  RequireMatrixNear(by_mass.inertia, by_density.inertia * (0.5 / by_density.mass), 1e-15);

  object.dynamic = false;
  REQUIRE_THROWS_AS(ComputeMassProperties(object), std::invalid_argument);
}

TEST_CASE("convex hull of a 4×4×4 lattice (many coplanar and collinear points) is the cube",
          "[hull]") {
  // Turned about a general axis so that coplanarity holds only up to rounding.
  const Matrix3d turn =
      Eigen::AngleAxisd(0.4, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vector3d centre(0.2, 0.1, -0.3);
  for (const bool turned : {false, true}) {
    std::vector<Vector3d> pts;
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        for (int k = 0; k < 4; ++k) {
          const Vector3d p = Vector3d(i, j, k) / 3.0 * 0.2 - Vector3d::Constant(0.1);
          pts.push_back(centre + (turned ? Matrix3d(turn) : Matrix3d::Identity()) * p);
        }
      }
    }
    std::mt19937 rng(3);
    std::shuffle(pts.begin(), pts.end(), rng);
    const MassProperties hull = ShapeMassProperties(Convex(pts), 1.0);
    const MassProperties box = ShapeMassProperties(
        Box(Vector3d::Constant(0.1), centre, turned ? Matrix3d(turn) : Matrix3d::Identity()), 1.0);
    INFO("turned " << turned);
    REQUIRE(hull.volume == Approx(box.volume).epsilon(1e-9));
    RequireVectorNear(hull.com, centre, 1e-12);
    RequireMatrixNear(hull.inertia, box.inertia, 1e-14);
  }
}
