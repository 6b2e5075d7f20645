#include "haptel/config/blimp_gesture.hpp"

#include "archives.hpp"
#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void BlimpGestureConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

BlimpGestureConfig LoadBlimpGesture(const std::filesystem::path& file) {
  return config_detail::LoadFile<BlimpGestureConfig>(file,
                                                     [](YamlMap& root, BlimpGestureConfig& g) {
                                                       if (g.name != "blimp-gesture")
                                                         root.Fail("name", "'blimp-gesture'");
                                                     });
}

}  // namespace haptel
