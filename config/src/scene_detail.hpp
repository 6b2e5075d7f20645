#pragma once
// What the two scene readers (scene.cpp: YAML, scene_xml.cpp: MHaptic XML)
// share: limits and checks.
#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

#include "haptel/config/scene.hpp"

namespace haptel::config_detail {

constexpr double kMaxCoordinate = 1e4;                   // m
constexpr double kMinSize = 1e-6;                        // m
constexpr double kMaxSize = 1e3;                         // m
constexpr double kMinMass = 1e-6, kMaxMass = 1e5;        // kg
constexpr double kMinDensity = 1e-3, kMaxDensity = 1e5;  // kg/m³
constexpr double kMaxFriction = 2.0;
constexpr std::size_t kMaxConvexPoints = 64;

/// A 3×3 matrix, row by row, that is a rotation within rounding of the file's
/// digits, returned re-orthonormalised in `out`. Empty when fine, else what
/// was expected.
std::string ToRotation(const std::vector<double>& rows, Eigen::Matrix3d& out);

/// Why a dynamic object cannot be a rigid body (what was expected), or "".
std::string CheckMassProperties(const SceneObject& object);

}  // namespace haptel::config_detail
