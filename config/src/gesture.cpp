#include "haptel/config/gesture.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/yaml_map.hpp"
#include "shared_control_section.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void GestureConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (shared_control.enabled) check::Nested("shared_control", shared_control);
}

GestureConfig LoadGesture(const std::filesystem::path& file) {
  return config_detail::LoadFile<GestureConfig>(file, [](YamlMap& root, GestureConfig& g) {
    if (!LoadsInto(g.name, typeid(GestureConfig)))
      root.Fail("name", NamesLoadingInto(typeid(GestureConfig)));
    config_detail::CheckSharedControl(root, g.name, typeid(GestureConfig), g.shared_control);
  });
}

}  // namespace haptel
