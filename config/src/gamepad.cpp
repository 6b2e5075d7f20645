#include "haptel/config/gamepad.hpp"

#include <array>
#include <utility>

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

namespace {
constexpr std::array<std::pair<const char*, GamepadDeadman>, 7> kDeadmen{{
    {"none", GamepadDeadman::kNone},
    {"a", GamepadDeadman::kA},
    {"b", GamepadDeadman::kB},
    {"x", GamepadDeadman::kX},
    {"y", GamepadDeadman::kY},
    {"left_shoulder", GamepadDeadman::kLeftShoulder},
    {"right_shoulder", GamepadDeadman::kRightShoulder},
}};
}  // namespace

GamepadConfig LoadGamepad(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  GamepadConfig g;
  g.file = file;
  g.name = root.String("name", g.name);
  if (g.name != "gamepad") root.Fail("name", "'gamepad'");
  g.dead_zone = root.Number("dead_zone", g.dead_zone, 0.0, 0.9);
  g.trigger_dead_zone = root.Number("trigger_dead_zone", g.trigger_dead_zone, 0.0, 0.9);

  const std::string turn = root.String("turn_axis", "left_x");
  if (turn == "left_x") {
    g.turn_axis = GamepadTurnAxis::kLeftX;
  } else if (turn == "right_x") {
    g.turn_axis = GamepadTurnAxis::kRightX;
  } else {
    root.Fail("turn_axis", "one of: left_x, right_x");
  }

  g.turn_share = root.Number("turn_share", g.turn_share, 0.0, 1.0);

  const std::string deadman = root.String("deadman", "left_shoulder");
  bool known = false;
  for (const auto& [word, value] : kDeadmen) {
    if (deadman == word) {
      g.deadman = value;
      known = true;
    }
  }
  if (!known) root.Fail("deadman", "one of: a, b, x, y, left_shoulder, right_shoulder, none");

  g.command_rate_hz = root.Number("command_rate_hz", g.command_rate_hz, 1.0, 1000.0);
  root.Finish();
  return g;
}

}  // namespace haptel
