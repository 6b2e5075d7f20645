#include "haptel/config/blimp_manual.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpManualConfig::ValidateOrThrow() const {
  if (!LoadsInto(name, typeid(BlimpManualConfig)))
    check::Fail("name", NamesLoadingInto(typeid(BlimpManualConfig)));
  config_detail::CheckFields(*this);
}

BlimpManualConfig LoadBlimpManual(const std::filesystem::path& file) {
  return config_detail::LoadFile<BlimpManualConfig>(file, [](YamlMap& root, BlimpManualConfig& c) {
    if (!LoadsInto(c.name, typeid(BlimpManualConfig)))
      root.Fail("name", NamesLoadingInto(typeid(BlimpManualConfig)));
  });
}

}  // namespace haptel
