#pragma once
/// @file The blimp's interfaces (the gesture cockpit, a person's keys or game
/// controller) on the family-templated base every interface shares
/// (interface.hpp): seven channels out, the hands, the head and a person's
/// input in.
#include <cstdint>

#include "haptel/core/blimp_command.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::interfaces {

/// Where the operator looks, relative to straight ahead, rad.
struct HeadDirection {
  double pan = 0.0;   ///< positive: left
  double tilt = 0.0;  ///< positive: up
};

/// What a blimp interface reads each tick besides the HAL.
struct BlimpReading {
  InputState person;   ///< a person's keys and controller
  HeadDirection head;  ///< where the pilot looks: the camera follows
  int64_t now_ns = 0;  ///< the HAL's clock, for the fields' stamps
};

/// The blimp: seven channels, and the command a pilot holds their hands for.
struct BlimpFamily {
  using Command = BlimpCommand;
  using Intent = BlimpCommand;
  using Reading = BlimpReading;
};

using BlimpInterface = Interface<BlimpFamily>;

}  // namespace haptel::interfaces
