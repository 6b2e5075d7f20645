#include "haptel/config/gesture.hpp"

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

GestureConfig LoadGesture(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  GestureConfig g;
  g.file = file;
  g.name = root.String("name", g.name);
  if (g.name != "gesture") root.Fail("name", "'gesture' (the only interface so far)");
  g.neutral = root.Vec3("neutral", g.neutral, -1.0, 1.0);
  g.dead_zone = root.Number("dead_zone", g.dead_zone, 0.0, 0.2);
  g.full_forward = root.Number("full_forward", g.full_forward, 0.005, 0.5);
  g.full_turn = root.Number("full_turn", g.full_turn, 0.005, 0.5);
  g.turn_share = root.Number("turn_share", g.turn_share, 0.0, 1.0);
  g.field_stiffness = root.Number("field_stiffness", g.field_stiffness, 0.0, 2000.0);
  g.field_stiffness_growth =
      root.Number("field_stiffness_growth", g.field_stiffness_growth, 0.0, 1e5);
  g.field_damping = root.Number("field_damping", g.field_damping, 0.0, 200.0);
  g.wall_stiffness = root.Number("wall_stiffness", g.wall_stiffness, 0.0, 1e5);
  g.wall_release_s = root.Number("wall_release_s", g.wall_release_s, 0.0, 10.0);
  g.command_rate_hz = root.Number("command_rate_hz", g.command_rate_hz, 1.0, 1000.0);
  root.Finish();
  return g;
}

}  // namespace haptel
