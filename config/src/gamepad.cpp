#include "haptel/config/gamepad.hpp"

#include <array>
#include <utility>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void GamepadConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

GamepadConfig LoadGamepad(const std::filesystem::path& file) {
  return config_detail::LoadFile<GamepadConfig>(file, [](YamlMap& root, GamepadConfig& g) {
    if (!LoadsInto(g.name, typeid(GamepadConfig)))
      root.Fail("name", NamesLoadingInto(typeid(GamepadConfig)));
  });
}

}  // namespace haptel
