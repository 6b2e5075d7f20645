#pragma once
/// @file What a vehicle's range sensors see: a planar scan of beams fanned
/// evenly about the vehicle's heading (sonars, or a laser scanner's sectors),
/// as sensor_msgs/LaserScan lays one out. Fixed capacity, so that a scan is
/// copied between threads and through the session loop without allocating.
#include <array>
#include <cstddef>

namespace haptel {

/// The most beams a scan carries (the link's bound too: link/idl/haptel.idl).
inline constexpr int kMaxRangeBeams = 32;

struct RangeScan {
  /// Beams in use; 0: the vehicle has no range sensors (the CAN robot, with
  /// only its bumpers), and nothing may be concluded from the scan.
  int count = 0;
  double angle_min = 0.0;        ///< rad of beam 0 from the heading, counter-clockwise positive
  double angle_increment = 0.0;  ///< rad from one beam to the next
  /// m: a beam that meets nothing within it reads exactly this.
  double range_max = 0.0;
  /// m from the vehicle's centre along each beam, [0, range_max].
  std::array<float, kMaxRangeBeams> ranges{};

  double Angle(int beam) const { return angle_min + angle_increment * beam; }
  /// The beam met something (it reads less than its maximum range).
  bool Hit(int beam) const { return ranges[static_cast<size_t>(beam)] < range_max; }
};

}  // namespace haptel
