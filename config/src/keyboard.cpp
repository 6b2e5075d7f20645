#include "haptel/config/keyboard.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void KeyboardConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

KeyboardConfig LoadKeyboard(const std::filesystem::path& file) {
  return config_detail::LoadFile<KeyboardConfig>(file, [](YamlMap& root, KeyboardConfig& k) {
    if (!LoadsInto(k.name, typeid(KeyboardConfig)))
      root.Fail("name", NamesLoadingInto(typeid(KeyboardConfig)));
  });
}

}  // namespace haptel
