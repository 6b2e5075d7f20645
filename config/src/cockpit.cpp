#include "haptel/config/cockpit.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/yaml_map.hpp"
#include "shared_control_section.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

void CockpitConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (!(wheel_max_angle_deg >= 10.0 && wheel_max_angle_deg < 180.0)) {
    check::Fail("wheel.max_angle_deg", "a number in [10, 180) (the hinge's end stops, ±)");
  }
  if (wheel_full_turn_deg > wheel_max_angle_deg) {
    check::Fail("wheel.full_turn_deg", "full_turn_deg <= max_angle_deg", {"wheel.max_angle_deg"});
  }

  if (shared_control.enabled) check::Nested("shared_control", shared_control);
}

CockpitConfig LoadCockpit(const std::filesystem::path& file) {
  return config_detail::LoadFile<CockpitConfig>(file, [](YamlMap& root, CockpitConfig& c) {
    if (!LoadsInto(c.name, typeid(CockpitConfig)))
      root.Fail("name", NamesLoadingInto(typeid(CockpitConfig)));
    config_detail::CheckSharedControl(root, c.name, typeid(CockpitConfig), c.shared_control);
  });
}

}  // namespace haptel
