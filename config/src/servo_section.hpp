#pragma once
#include "haptel/config/archives.hpp"
#include "haptel/config/servo.hpp"

namespace haptel::config_detail {

/// Reads a `servo:` section (and finishes it, and its `channels:` mapping,
/// which must hold all seven channels, each with its `channel`); the
/// enclosing config's ValidateOrThrow checks the values. `baud` defaults to
/// 9600 for protocol sc8000.
inline ServoControllerConfig ReadServoController(YamlMap& section) {
  return ReadSection<ServoControllerConfig>(section);
}

}  // namespace haptel::config_detail
