#pragma once
/// @file The blimp course's geometry as the lap timer and the pilot use it:
/// gate frames and the buildings near a path.
#include <Eigen/Core>
#include <vector>

#include "haptel/config/blimp_course.hpp"

namespace haptel::mediator {

/// A gate's frame: its opening is centre ± left·half_width ± z·half_height.
struct BlimpGateFrame {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitX();  ///< horizontal unit direction of travel
  Eigen::Vector3d left = Eigen::Vector3d::UnitY();     ///< horizontal, to the left of forward
  double half_width = 0.0;
  double half_height = 0.0;

  /// Signed distance of p past the gate's plane (> 0: beyond it).
  double Along(const Eigen::Vector3d& p) const { return (p - centre).dot(forward); }
};

BlimpGateFrame MakeGateFrame(const BlimpGateSpec& gate);
std::vector<BlimpGateFrame> MakeGateFrames(const BlimpCourseConfig& course);

/// How a crossing of a gate's plane counts.
enum class BlimpGateCrossing { kPassed, kMissed, kIgnored };

/// A crossing of the gate's plane at p: through the opening, near it (within
/// `near_widths` gate widths of the centre: the gate is missed), or far away
/// (not a crossing of this gate at all).
BlimpGateCrossing ClassifyCrossing(const BlimpGateFrame& gate, const Eigen::Vector3d& p,
                                   double near_widths = 3.0);

/// Horizontal distance from (x, y) to a building's footprint (0 inside).
double FootprintDistance(const BlimpBuildingSpec& building, double x, double y);
/// Horizontal distance from the segment a–b to a building's footprint (0
/// when it crosses it).
double FootprintDistance(const BlimpBuildingSpec& building, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b);

}  // namespace haptel::mediator
