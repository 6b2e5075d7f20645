#include "haptel/config/blimp_gesture.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpGestureConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

BlimpGestureConfig LoadBlimpGesture(const std::filesystem::path& file) {
  return config_detail::LoadFile<BlimpGestureConfig>(
      file, [](YamlMap& root, BlimpGestureConfig& g) {
        if (!LoadsInto(g.name, typeid(BlimpGestureConfig)))
          root.Fail("name", NamesLoadingInto(typeid(BlimpGestureConfig)));
      });
}

}  // namespace haptel
