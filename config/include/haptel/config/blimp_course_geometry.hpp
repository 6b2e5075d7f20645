#pragma once
/// @file The blimp course's geometry, one definition for everything that
/// reads a course: its validation, the lap timer, the automatic pilot and
/// the synthetic camera — gate frames, how a crossing of a gate's plane
/// counts, the buildings' footprints, and the landing ground.
#include <Eigen/Core>
#include <optional>
#include <vector>

#include "haptel/config/blimp_course.hpp"

namespace haptel {

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

/// The motion p0 → p1 through the gate's plane in its direction of travel.
struct BlimpGatePass {
  double fraction = 0.0;  ///< along p0 → p1 where it crosses, [0, 1]
  BlimpGateCrossing crossing = BlimpGateCrossing::kIgnored;
};
/// Where p0 → p1 crosses the gate's plane forwards, and how it counts;
/// nullopt when it does not cross it forwards.
std::optional<BlimpGatePass> CrossGate(const BlimpGateFrame& gate, const Eigen::Vector3d& p0,
                                       const Eigen::Vector3d& p1);

/// A building's footprint on the ground: its rectangle turned by its yaw
/// (the turn worked out once).
class BlimpFootprint {
 public:
  explicit BlimpFootprint(const BlimpBuildingSpec& building);
  double height() const { return height_; }
  /// Horizontal distance from p to the footprint (0 inside).
  double Distance(const Eigen::Vector2d& p) const;
  /// Whether the segment a–b meets the footprint.
  bool Meets(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  /// Horizontal distance from the segment a–b to the footprint (0 when it meets it).
  double Distance(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

 private:
  /// p in the footprint's own frame (axis-aligned, centred).
  Eigen::Vector2d Local(const Eigen::Vector2d& p) const;
  bool MeetsLocal(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;

  Eigen::Vector2d centre_;
  Eigen::Vector2d half_;
  double cos_yaw_, sin_yaw_;
  double height_;
};

std::vector<BlimpFootprint> MakeFootprints(const BlimpCourseConfig& course);

/// On the landing ground: inside the landing circle, and lower than the
/// lap's take-off threshold above `start_z` (where the blimp rested).
bool OnLandingGround(const BlimpCourseConfig& course, const Eigen::Vector3d& p, double start_z);

}  // namespace haptel
