#include "haptel/config/shared_control.hpp"

#include "archives.hpp"
#include "haptel/config/check.hpp"
#include "shared_control_section.hpp"

namespace haptel {

namespace check = config_check;

void SharedControlConfig::ValidateOrThrow() const {
  check::Number("horizon_s", horizon_s, 0.1, 10.0);
  // The sim operator's muscle tops out at 8 N: above 15 N a person may not push through.
  check::Number("max_force", max_force, 0.0, 15.0);
  check::Number("stiffness", stiffness, 0.0, 2000.0);
  check::Number("clearance", clearance, 0.0, 1.0);
}

namespace config_detail {

void CheckSharedControl(YamlMap& root, const std::string& name, const std::string& shared_name,
                        SharedControlConfig& out) {
  const bool shared = name == shared_name;
  if (shared != root.Has("shared_control")) {
    root.Fail("shared_control",
              shared ? "a 'shared_control' section (horizon_s, max_force, stiffness, clearance)"
                     : "no 'shared_control' section on '" + name + "' (name the file '" +
                           shared_name + "')");
  }
  out.enabled = shared;
}

}  // namespace config_detail
}  // namespace haptel
