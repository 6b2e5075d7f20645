#include "haptel/config/gesture.hpp"

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void SharedControlConfig::ValidateOrThrow() const {
  check::Number("horizon_s", horizon_s, 0.1, 10.0);
  // The sim operator's muscle tops out at 8 N: above 15 N a person may not push through.
  check::Number("max_force", max_force, 0.0, 15.0);
  check::Number("stiffness", stiffness, 0.0, 2000.0);
  check::Number("clearance", clearance, 0.0, 1.0);
}

void GestureConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Vec3("neutral", neutral, -1.0, 1.0);
  check::Number("dead_zone", dead_zone, 0.0, 0.2);
  check::Number("full_forward", full_forward, 0.005, 0.5);
  check::Number("full_turn", full_turn, 0.005, 0.5);
  check::Number("turn_share", turn_share, 0.0, 1.0);
  check::Number("field_stiffness", field_stiffness, 0.0, 2000.0);
  check::Number("field_stiffness_growth", field_stiffness_growth, 0.0, 1e5);
  check::Number("field_damping", field_damping, 0.0, 200.0);
  check::Number("wall_stiffness", wall_stiffness, 0.0, 1e5);
  check::Number("wall_release_s", wall_release_s, 0.0, 10.0);
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);
  if (shared_control.enabled) check::Nested("shared_control", shared_control);
}

GestureConfig LoadGesture(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  GestureConfig g;
  g.file = file;
  g.name = root.String("name", g.name);
  // The name says which loader reads a file (InterfaceName); in code it is a label.
  if (g.name != "gesture" && g.name != "gesture-shared") root.Fail("name", "'gesture' or 'gesture-shared'");
  g.neutral = root.Vec3("neutral", g.neutral);
  g.dead_zone = root.Number("dead_zone", g.dead_zone);
  g.full_forward = root.Number("full_forward", g.full_forward);
  g.full_turn = root.Number("full_turn", g.full_turn);
  g.turn_share = root.Number("turn_share", g.turn_share);
  g.field_stiffness = root.Number("field_stiffness", g.field_stiffness);
  g.field_stiffness_growth = root.Number("field_stiffness_growth", g.field_stiffness_growth);
  g.field_damping = root.Number("field_damping", g.field_damping);
  g.wall_stiffness = root.Number("wall_stiffness", g.wall_stiffness);
  g.wall_release_s = root.Number("wall_release_s", g.wall_release_s);
  g.command_rate_hz = root.Number("command_rate_hz", g.command_rate_hz);
  // gesture-shared is the gesture interface with shared control: the section
  // is what makes it so, and it has no meaning on plain gesture.
  const bool shared = g.name == "gesture-shared";
  if (shared != root.Has("shared_control")) {
    root.Fail("shared_control", shared ? "a 'shared_control' section (horizon_s, max_force, stiffness, clearance)"
                                       : "no 'shared_control' section on 'gesture' (name the file 'gesture-shared')");
  }
  if (shared) {
    YamlMap section = root.Map("shared_control");
    SharedControlConfig& c = g.shared_control;
    c.enabled = true;
    c.horizon_s = section.Number("horizon_s", c.horizon_s);
    c.max_force = section.Number("max_force", c.max_force);
    c.stiffness = section.Number("stiffness", c.stiffness);
    c.clearance = section.Number("clearance", c.clearance);
    section.Finish();
  }
  root.Finish();
  config_detail::ValidateIn(root, g);
  return g;
}

}  // namespace haptel
