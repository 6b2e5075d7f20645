#include "haptel/config/gesture.hpp"

#include "haptel/config/check.hpp"
#include "shared_control_section.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::ReadSharedControl;
using config_detail::YamlMap;
namespace check = config_check;

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
  if (g.name != "gesture" && g.name != "gesture-shared")
    root.Fail("name", "'gesture' or 'gesture-shared'");
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
  ReadSharedControl(root, g.name, "gesture-shared", g.shared_control);
  root.Finish();
  config_detail::ValidateIn(root, g);
  return g;
}

}  // namespace haptel
