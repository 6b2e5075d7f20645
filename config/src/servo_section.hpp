#pragma once
#include "haptel/config/servo.hpp"
#include "yaml_map.hpp"

namespace haptel::config_detail {

/// Reads a `servo:` section (and finishes it, and its `channels:` mapping,
/// which must hold all seven channels, each with its `channel`); the
/// enclosing config's ValidateOrThrow checks the values. `baud` defaults to
/// 9600 for protocol sc8000.
ServoControllerConfig ReadServoController(YamlMap& section);

}  // namespace haptel::config_detail
