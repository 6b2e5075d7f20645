#include "haptel/config/keyboard.hpp"

#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

KeyboardConfig LoadKeyboard(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  KeyboardConfig k;
  k.file = file;
  k.name = root.String("name", k.name);
  if (k.name != "keyboard") root.Fail("name", "'keyboard'");
  k.repeat_s = root.Number("repeat_s", k.repeat_s, 0.01, 2.0);
  k.release_to_zero = root.Bool("release_to_zero", k.release_to_zero);
  k.turn_share = root.Number("turn_share", k.turn_share, 0.0, 1.0);
  k.command_rate_hz = root.Number("command_rate_hz", k.command_rate_hz, 1.0, 1000.0);
  root.Finish();
  return k;
}

}  // namespace haptel
