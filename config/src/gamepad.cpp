#include "haptel/config/gamepad.hpp"

#include <array>
#include <utility>

#include "archives.hpp"
#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void GamepadConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

GamepadConfig LoadGamepad(const std::filesystem::path& file) {
  return config_detail::LoadFile<GamepadConfig>(file, [](YamlMap& root, GamepadConfig& g) {
    if (g.name != "gamepad") root.Fail("name", "'gamepad'");
  });
}

}  // namespace haptel
