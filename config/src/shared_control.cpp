#include "haptel/config/shared_control.hpp"

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/interface_kinds.hpp"
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

void CheckSharedControl(YamlMap& root, const std::string& name, const std::type_info& config,
                        SharedControlConfig& out) {
  const InterfaceKindInfo* kind = FindInterfaceKind(name);
  const bool shared = kind != nullptr && kind->shared_control;
  if (shared != root.Has("shared_control")) {
    // The interface of the same file's kind that has shared control.
    std::string shared_name;
    for (const InterfaceKindInfo& k : InterfaceKinds()) {
      if (k.shared_control && k.config != nullptr && *k.config == config) shared_name = k.name;
    }
    root.Fail("shared_control",
              shared ? "a 'shared_control' section (horizon_s, max_force, stiffness, clearance)"
                     : "no 'shared_control' section on '" + name + "' (name the file '" +
                           shared_name + "')");
  }
  out.enabled = shared;
}

}  // namespace config_detail
}  // namespace haptel
