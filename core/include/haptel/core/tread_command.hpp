#pragma once
/// @file What the robot is told: each tread's command in [-1, 1] of its top
/// speed (the vehicle quantises it to the brick's speed levels). A flat value
/// type shared by the interfaces that make it, the DDS link that carries it
/// and the vehicle that obeys it, as BlimpCommand is the blimp's.

namespace haptel {

struct TreadCommand {
  double left = 0.0;   ///< -1..1, forward positive
  double right = 0.0;  ///< -1..1, forward positive
};

}  // namespace haptel
