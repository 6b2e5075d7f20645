#pragma once
/// @file Mass, centre of mass and inertia tensor of a scene object from its
/// shapes, for the physics world's rigid bodies.
///
/// Closed forms for box, sphere and capsule (a cylinder plus two exact
/// hemispheres); a convex shape is the convex hull of its points, decomposed
/// into tetrahedra. Offset and rotated shapes are moved into the object frame
/// (rotation, then the parallel-axis theorem). Shapes are summed as if they
/// did not overlap: overlapping volume counts twice. Planes have no finite
/// volume and are rejected.
///
/// All functions throw std::invalid_argument for bad input (non-positive
/// density, a plane, a degenerate hull); the scene loaders turn that into a
/// ConfigError naming the file and line.
#include <Eigen/Core>
#include <array>
#include <vector>

#include "haptel/config/scene.hpp"

namespace haptel {

struct MassProperties {
  double mass = 0.0;                                  ///< kg
  double volume = 0.0;                                ///< m³
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      ///< centre of mass, object frame, m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< about com, object-frame axes, kg·m²
};

/// One shape of the given density (kg/m³), in the object frame (its pose applied).
MassProperties ShapeMassProperties(const SceneShape& shape, double density);

/// The sum of parts given in one frame: masses add, the com is the mass-weighted
/// mean, inertias are moved to it by the parallel-axis theorem.
MassProperties CombineMassProperties(const std::vector<MassProperties>& parts);

/// All shapes at one density.
MassProperties ComputeMassProperties(const std::vector<SceneShape>& shapes, double density);

/// A dynamic object's mass properties. Each shape has its own density
/// (SceneShape::density) when it gives one, else the object's density; with
/// no object density the result is then scaled so the total is the object's
/// mass (shapes without a density of their own count as uniform).
MassProperties ComputeMassProperties(const SceneObject& object);

/// The mass of each shape of a dynamic object (kg, in shape order, summing to
/// the object's mass), by the rule of ComputeMassProperties.
std::vector<double> ShapeMasses(const SceneObject& object);

/// inertia about a point displaced by `offset` from the centre of mass
/// (parallel-axis theorem): I + m (|d|² 1 − d dᵀ).
Eigen::Matrix3d ShiftInertia(const Eigen::Matrix3d& inertia_about_com, double mass,
                             const Eigen::Vector3d& offset);

/// Principal moments (ascending) and axes: inertia = axes · diag(moments) · axesᵀ,
/// axes a proper rotation (det +1; its columns are the principal axes).
struct PrincipalInertia {
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
};
PrincipalInertia Diagonalize(const Eigen::Matrix3d& inertia);

/// The convex hull of a small point set (incremental, O(n²); meant for ≤ 64
/// points): triangles index into `points`, counter-clockwise seen from outside.
/// Points inside or on the hull within a relative tolerance are not vertices;
/// coplanar hull faces may be split into several triangles. Throws
/// std::invalid_argument for fewer than 4 points or points spanning no volume.
struct ConvexHull {
  std::vector<std::array<int, 3>> triangles;
};
ConvexHull ComputeConvexHull(const std::vector<Eigen::Vector3d>& points);

}  // namespace haptel
