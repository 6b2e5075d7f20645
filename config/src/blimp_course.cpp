#include "haptel/config/blimp_course.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <set>
#include <string>

#include "haptel/config/blimp_course_geometry.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

/// No course is larger than this (m from the origin, each coordinate).
constexpr double kMaxCoordinate = 1e5;

/// How far the start must be from any building's footprint (m): room for
/// a 6.75 m hull to rest there and swing in the wind.
constexpr double kBlimpStartClearance = 4.0;

std::string Text(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

void Point2(const std::string& key, const std::array<double, 2>& p) {
  for (double v : p) {
    if (!(std::abs(v) <= kMaxCoordinate)) {
      check::Fail(key,
                  "a point [x, y] within " + check::Range(-kMaxCoordinate, kMaxCoordinate) + " m");
    }
  }
}

std::string BuildingName(const std::vector<BlimpBuildingSpec>& buildings, size_t i) {
  return "building '" + buildings[i].name + "' (buildings[" + std::to_string(i) + "])";
}

}  // namespace

void BlimpCourseConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Number("lap_cap_s", lap_cap_s, 1.0, 24 * 3600.0);
  check::Number("crash_speed", crash_speed, 0.05, 50.0);
  check::Number("takeoff_height", takeoff_height, 0.05, 100.0);
  Point2("start.position", start.position);
  check::Number("start.heading_deg", start.heading_deg, -360.0, 360.0);

  if (gates.empty())
    check::Fail("gates", "a list of at least one gate {name, centre, heading_deg, width, height}");
  std::set<std::string> gate_names;
  for (size_t i = 0; i < gates.size(); ++i) {
    const BlimpGateSpec& g = gates[i];
    const std::string key = "gates[" + std::to_string(i) + "]";
    check::NonEmpty(key + ".name", g.name);
    if (!gate_names.insert(g.name).second) check::Fail(key + ".name", "a name no other gate has");
    Point2(key + ".centre", {g.centre[0], g.centre[1]});
    check::Number(key + ".heading_deg", g.heading_deg, -360.0, 360.0);
    check::Number(key + ".width", g.width, 1.0, 1000.0);
    check::Number(key + ".height", g.height, 1.0, 1000.0);
    if (!(g.centre[2] >= g.height / 2 && g.centre[2] <= 1000.0)) {
      throw ConfigFieldError(
          key + ".centre", "an opening above the ground: centre z >= height / 2 and <= 1000 m",
          {key + ".height"}, "z " + Text(g.centre[2]) + " with height " + Text(g.height));
    }
  }

  std::set<std::string> building_names;
  for (size_t i = 0; i < buildings.size(); ++i) {
    const BlimpBuildingSpec& b = buildings[i];
    const std::string key = "buildings[" + std::to_string(i) + "]";
    check::NonEmpty(key + ".name", b.name);
    if (!building_names.insert(b.name).second)
      check::Fail(key + ".name", "a name no other building has");
    Point2(key + ".centre", b.centre);
    for (double s : b.size) {
      if (!(s >= 0.1 && s <= 1e4))
        check::Fail(key + ".size", "a list of 2 numbers [sx, sy] in [0.1, 10000] m");
    }
    check::Number(key + ".height", b.height, 0.1, 1000.0);
    check::Number(key + ".yaw_deg", b.yaw_deg, -360.0, 360.0);
  }

  Point2("landing.centre", landing.centre);
  check::Positive("landing.radius", landing.radius);
  check::Number("landing.radius", landing.radius, 0.0, 1e4);
  check::Positive("landing.max_speed", landing.max_speed);
  check::Number("landing.max_speed", landing.max_speed, 0.0, 20.0);

  // The places against the buildings.
  for (size_t j = 0; j < buildings.size(); ++j) {
    const BlimpFootprint f(buildings[j]);
    for (size_t i = 0; i < gates.size(); ++i) {
      const BlimpGateSpec& g = gates[i];
      const BlimpGateFrame frame = MakeGateFrame(g);
      const Eigen::Vector2d centre = frame.centre.head<2>(),
                            half_span = frame.left.head<2>() * frame.half_width;
      const bool below_roof = g.centre[2] - g.height / 2 < buildings[j].height;
      if (below_roof && f.Meets(centre - half_span, centre + half_span)) {
        throw ConfigFieldError("gates[" + std::to_string(i) + "].centre",
                               "a gate clear of the buildings",
                               {"buildings[" + std::to_string(j) + "].centre"},
                               "an opening that meets " + BuildingName(buildings, j));
      }
    }
    if (f.Distance(Eigen::Vector2d(landing.centre[0], landing.centre[1])) < landing.radius) {
      throw ConfigFieldError("landing.centre", "a landing circle clear of the buildings",
                             {"landing.radius"},
                             "a circle that overlaps " + BuildingName(buildings, j));
    }
    if (f.Distance(Eigen::Vector2d(start.position[0], start.position[1])) < kBlimpStartClearance) {
      throw ConfigFieldError(
          "start.position",
          "a start at least " + Text(kBlimpStartClearance) + " m from every building", {},
          "a start " + Text(f.Distance(Eigen::Vector2d(start.position[0], start.position[1]))) +
              " m from " + BuildingName(buildings, j));
    }
  }
}

BlimpCourseConfig LoadBlimpCourse(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  BlimpCourseConfig c;
  c.file = file;
  c.name = root.RequireString("name");
  c.lap_cap_s = root.Number("lap_cap_s", c.lap_cap_s);
  c.crash_speed = root.Number("crash_speed", c.crash_speed);
  c.takeoff_height = root.Number("takeoff_height", c.takeoff_height);

  if (!root.IsMap("start")) root.Fail("start", "a mapping {position: [x, y], heading_deg}");
  YamlMap start = root.Map("start");
  const Vec2 position = start.Point("position");
  c.start.position = {position.x(), position.y()};
  c.start.heading_deg = start.Number("heading_deg", c.start.heading_deg);
  start.Finish();

  if (!root.Has("gates"))
    root.Fail("gates", "a list of at least one gate {name, centre, heading_deg, width, height}");
  for (YamlMap& g : root.MapList("gates")) {
    BlimpGateSpec spec;
    spec.name = g.RequireString("name");
    const std::vector<double> centre = g.Numbers("centre", 3, "numbers [x, y, z] in metres");
    spec.centre = {centre[0], centre[1], centre[2]};
    spec.heading_deg = g.RequireNumber("heading_deg");
    spec.width = g.RequireNumber("width");
    spec.height = g.RequireNumber("height");
    g.Finish();
    c.gates.push_back(spec);
  }
  for (YamlMap& b : root.MapList("buildings")) {
    BlimpBuildingSpec spec;
    spec.name = b.RequireString("name");
    const Vec2 centre = b.Point("centre");
    spec.centre = {centre.x(), centre.y()};
    const std::vector<double> size = b.Numbers("size", 2, "numbers [sx, sy] in metres");
    spec.size = {size[0], size[1]};
    spec.height = b.RequireNumber("height");
    spec.yaw_deg = b.Number("yaw_deg", spec.yaw_deg);
    b.Finish();
    c.buildings.push_back(spec);
  }

  if (!root.IsMap("landing")) root.Fail("landing", "a mapping {centre: [x, y], radius, max_speed}");
  YamlMap landing = root.Map("landing");
  const Vec2 centre = landing.Point("centre");
  c.landing.centre = {centre.x(), centre.y()};
  c.landing.radius = landing.RequireNumber("radius");
  c.landing.max_speed = landing.Number("max_speed", c.landing.max_speed);
  landing.Finish();

  root.Finish();
  config_detail::ValidateIn(root, c);
  return c;
}

}  // namespace haptel
