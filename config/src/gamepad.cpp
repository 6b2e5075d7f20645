#include "haptel/config/gamepad.hpp"

#include <array>
#include <utility>

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

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

void GamepadConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Number("dead_zone", dead_zone, 0.0, 0.9);
  check::Number("trigger_dead_zone", trigger_dead_zone, 0.0, 0.9);
  if (turn_axis != GamepadTurnAxis::kLeftX && turn_axis != GamepadTurnAxis::kRightX) {
    check::Fail("turn_axis", "one of: left_x, right_x");
  }
  check::Number("turn_share", turn_share, 0.0, 1.0);
  bool known = false;
  for (const auto& entry : kDeadmen) known = known || entry.second == deadman;
  if (!known) check::Fail("deadman", "one of: a, b, x, y, left_shoulder, right_shoulder, none");
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);
}

GamepadConfig LoadGamepad(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  GamepadConfig g;
  g.file = file;
  g.name = root.String("name", g.name);
  // The name says which loader reads a file (InterfaceName); in code it is a label.
  if (g.name != "gamepad") root.Fail("name", "'gamepad'");
  g.dead_zone = root.Number("dead_zone", g.dead_zone);
  g.trigger_dead_zone = root.Number("trigger_dead_zone", g.trigger_dead_zone);

  const std::string turn = root.String("turn_axis", "left_x");
  if (turn == "left_x") {
    g.turn_axis = GamepadTurnAxis::kLeftX;
  } else if (turn == "right_x") {
    g.turn_axis = GamepadTurnAxis::kRightX;
  } else {
    root.Fail("turn_axis", "one of: left_x, right_x");
  }

  g.turn_share = root.Number("turn_share", g.turn_share);

  const std::string deadman = root.String("deadman", "left_shoulder");
  bool known = false;
  for (const auto& [word, value] : kDeadmen) {
    if (deadman == word) {
      g.deadman = value;
      known = true;
    }
  }
  if (!known) root.Fail("deadman", "one of: a, b, x, y, left_shoulder, right_shoulder, none");

  g.command_rate_hz = root.Number("command_rate_hz", g.command_rate_hz);
  root.Finish();
  config_detail::ValidateIn(root, g);
  return g;
}

}  // namespace haptel
