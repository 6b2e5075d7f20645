#pragma once
/// @file The blimp's course (thesis ch. 8.2.3: "a 5 minutes teleoperated
/// flight with a takeoff, and passage over buildings"): a start on the
/// ground, gates in the air to fly through in order, buildings standing on
/// the ground, and a landing zone.
///
/// Frames as everywhere: the world is x east, y north, z up; headings are
/// counter-clockwise from +x, in degrees in the file. A gate is a vertical
/// rectangular opening centred on `centre`, `width` across and `height`
/// high, to be flown through in the direction `heading_deg`. A building is
/// a box standing on the ground (z = 0), its footprint `size` turned by
/// `yaw_deg` about its centre.
#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace haptel {

struct BlimpStartSpec {
  std::array<double, 2> position{0.0, 0.0};  ///< m: where the blimp rests on the ground
  double heading_deg = 0.0;
};

struct BlimpGateSpec {
  std::string name;
  std::array<double, 3> centre{0.0, 0.0, 0.0};  ///< m: the opening's centre
  double heading_deg = 0.0;                     ///< the direction of travel through the gate
  double width = 0.0;                           ///< m, across the direction of travel
  double height = 0.0;                          ///< m
};

struct BlimpBuildingSpec {
  std::string name;
  std::array<double, 2> centre{0.0, 0.0};  ///< m, of the footprint
  std::array<double, 2> size{0.0, 0.0};    ///< m, along the building's own x and y
  double height = 0.0;                     ///< m above the ground
  double yaw_deg = 0.0;                    ///< the footprint's turn about its centre
};

struct BlimpLandingSpec {
  std::array<double, 2> centre{0.0, 0.0};  ///< m
  double radius = 0.0;                     ///< m
  double max_speed = 1.0;  ///< m/s: the blimp's speed on the ground for a landing to count
};

struct BlimpCourseConfig {
  std::string name;
  std::filesystem::path file;
  double lap_cap_s = 600.0;
  BlimpStartSpec start;
  std::vector<BlimpGateSpec> gates;
  std::vector<BlimpBuildingSpec> buildings;
  BlimpLandingSpec landing;
  /// m/s: a contact with a building or the ground closing faster than this
  /// is a crash (a touch below it is an obstacle touched).
  double crash_speed = 1.5;
  /// m: the lap starts when the centre of gravity first rises this far
  /// above where it rested at the start.
  double takeoff_height = 1.0;

  /// Throws ConfigFieldError ("gates[2].centre", "landing.radius") unless
  /// every value is in range, there is at least one gate, gate names and
  /// building names are unique, every gate's opening is above the ground and
  /// clear of every building, the landing circle (radius > 0) and the start
  /// (with room for the hull around it) are clear of every building.
  void ValidateOrThrow() const;
};

/// Loads and validates a course file. Throws ConfigError naming file:line,
/// the key and what was expected (unknown keys too).
BlimpCourseConfig LoadBlimpCourse(const std::filesystem::path& file);

}  // namespace haptel
