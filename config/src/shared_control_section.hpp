#pragma once
/// @file The rule on the `shared_control:` section the shared interfaces'
/// files share (gesture.cpp, cockpit.cpp); the section itself is read by
/// their Serialize.
#include <string>

#include "haptel/config/shared_control.hpp"
#include "yaml_map.hpp"

namespace haptel::config_detail {

/// An interface named `shared_name` (gesture-shared, cockpit-shared) is its
/// base interface with shared control: the section is what makes it so, and
/// it has no meaning on the others. Fails naming the key unless the section
/// is there exactly when `name == shared_name`; `out` is enabled when it is.
void CheckSharedControl(YamlMap& root, const std::string& name, const std::string& shared_name,
                        SharedControlConfig& out);

}  // namespace haptel::config_detail
