#include "haptel/config/blimp_manual.hpp"

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpManualConfig::ValidateOrThrow() const {
  if (!IsBlimpManual(name)) check::Fail("name", "'blimp-keys' or 'blimp-gamepad'");
  check::Whole("power_steps", power_steps, 1, 100);
  check::Whole("helix_steps", helix_steps, 1, 100);
  check::Whole("elevator_steps", elevator_steps, 1, 100);
  check::Number("repeat_s", repeat_s, 0.01, 2.0);
  check::Number("rudder_rate", rudder_rate, 0.1, 100.0);
  check::Number("dead_zone", dead_zone, 0.0, 0.9);
  check::Number("trigger_dead_zone", trigger_dead_zone, 0.0, 0.9);
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);
}

BlimpManualConfig LoadBlimpManual(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  BlimpManualConfig c;
  c.file = file;
  c.name = root.String("name", c.name);
  // The name says which loader reads a file (InterfaceName) and which input flies.
  if (!IsBlimpManual(c.name)) root.Fail("name", "'blimp-keys' or 'blimp-gamepad'");
  if (c.input() == BlimpManualInput::kKeys) {
    c.power_steps = root.Integer("power_steps", c.power_steps);
    c.helix_steps = root.Integer("helix_steps", c.helix_steps);
    c.elevator_steps = root.Integer("elevator_steps", c.elevator_steps);
    c.repeat_s = root.Number("repeat_s", c.repeat_s);
    c.rudder_rate = root.Number("rudder_rate", c.rudder_rate);
  } else {
    c.dead_zone = root.Number("dead_zone", c.dead_zone);
    c.trigger_dead_zone = root.Number("trigger_dead_zone", c.trigger_dead_zone);
  }
  c.command_rate_hz = root.Number("command_rate_hz", c.command_rate_hz);
  root.Finish();
  config_detail::ValidateIn(root, c);
  return c;
}

}  // namespace haptel
