#include "haptel/config/blimp_gesture.hpp"

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpGestureConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Vec3("right_neutral", right_neutral, -1.0, 1.0);
  check::Vec3("left_neutral", left_neutral, -1.0, 1.0);
  check::Number("dead_zone", dead_zone, 0.0, 0.2);
  check::Number("full_elevator", full_elevator, 0.005, 0.5);
  check::Number("full_rudder", full_rudder, 0.005, 0.5);
  check::Number("full_power", full_power, 0.005, 0.5);
  check::Number("full_helix", full_helix, 0.005, 0.5);
  check::Number("full_tail", full_tail, 0.005, 0.5);
  check::Number("field_stiffness", field_stiffness, 0.0, 2000.0);
  check::Number("field_stiffness_growth", field_stiffness_growth, 0.0, 1e5);
  check::Number("field_damping", field_damping, 0.0, 200.0);
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);
}

BlimpGestureConfig LoadBlimpGesture(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  BlimpGestureConfig g;
  g.file = file;
  g.name = root.String("name", g.name);
  if (g.name != "blimp-gesture") root.Fail("name", "'blimp-gesture'");
  g.right_neutral = root.Vec3("right_neutral", g.right_neutral);
  g.left_neutral = root.Vec3("left_neutral", g.left_neutral);
  g.dead_zone = root.Number("dead_zone", g.dead_zone);
  g.full_elevator = root.Number("full_elevator", g.full_elevator);
  g.full_rudder = root.Number("full_rudder", g.full_rudder);
  g.full_power = root.Number("full_power", g.full_power);
  g.full_helix = root.Number("full_helix", g.full_helix);
  g.full_tail = root.Number("full_tail", g.full_tail);
  g.field_stiffness = root.Number("field_stiffness", g.field_stiffness);
  g.field_stiffness_growth = root.Number("field_stiffness_growth", g.field_stiffness_growth);
  g.field_damping = root.Number("field_damping", g.field_damping);
  g.command_rate_hz = root.Number("command_rate_hz", g.command_rate_hz);
  root.Finish();
  config_detail::ValidateIn(root, g);
  return g;
}

}  // namespace haptel
