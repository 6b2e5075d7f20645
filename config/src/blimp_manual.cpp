#include "haptel/config/blimp_manual.hpp"

#include "archives.hpp"
#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpManualConfig::ValidateOrThrow() const {
  if (!IsBlimpManual(name)) check::Fail("name", "'blimp-keys' or 'blimp-gamepad'");
  config_detail::CheckFields(*this);
}

BlimpManualConfig LoadBlimpManual(const std::filesystem::path& file) {
  return config_detail::LoadFile<BlimpManualConfig>(file, [](YamlMap& root, BlimpManualConfig& c) {
    if (!IsBlimpManual(c.name)) root.Fail("name", "'blimp-keys' or 'blimp-gamepad'");
  });
}

}  // namespace haptel
