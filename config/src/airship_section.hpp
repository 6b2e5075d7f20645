#pragma once
#include "haptel/config/airship.hpp"
#include "yaml_map.hpp"

namespace haptel::config_detail {

/// Reads an `airship:` section (and finishes it); the enclosing config's
/// ValidateOrThrow checks the values. `aerodynamics` is not a file key: it
/// is for checking the model, never for flying.
AirshipConfig ReadAirship(YamlMap& section);

}  // namespace haptel::config_detail
