#pragma once
/// @file The rule on the `shared_control:` section the shared interfaces'
/// files share (gesture.cpp, cockpit.cpp); the section itself is read by
/// their Serialize.
#include <string>
#include <typeinfo>

#include "haptel/config/shared_control.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel::config_detail {

/// An interface whose row says `shared_control` (gesture-shared,
/// cockpit-shared) is its base interface with shared control: the section is
/// what makes it so, and it has no meaning on the others. Fails naming the
/// key unless the section is there exactly when the interface `name` has
/// shared control; `out` is enabled when it has. `config`: the struct the
/// file loads into, whose shared interface an error names.
void CheckSharedControl(YamlMap& root, const std::string& name, const std::type_info& config,
                        SharedControlConfig& out);

}  // namespace haptel::config_detail
