#include "haptel/config/keyboard.hpp"

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void KeyboardConfig::ValidateOrThrow() const {
  check::NonEmpty("name", name);
  check::Number("repeat_s", repeat_s, 0.01, 2.0);
  check::Number("turn_share", turn_share, 0.0, 1.0);
  check::Number("command_rate_hz", command_rate_hz, 1.0, 1000.0);
}

KeyboardConfig LoadKeyboard(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  KeyboardConfig k;
  k.file = file;
  k.name = root.String("name", k.name);
  // The name says which loader reads a file (InterfaceName); in code it is a label.
  if (k.name != "keyboard") root.Fail("name", "'keyboard'");
  k.repeat_s = root.Number("repeat_s", k.repeat_s);
  k.release_to_zero = root.Bool("release_to_zero", k.release_to_zero);
  k.turn_share = root.Number("turn_share", k.turn_share);
  k.command_rate_hz = root.Number("command_rate_hz", k.command_rate_hz);
  root.Finish();
  config_detail::ValidateIn(root, k);
  return k;
}

}  // namespace haptel
