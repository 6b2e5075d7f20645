#pragma once
/// @file The in-process robot of `haptel run --simulated-time`
/// (mediator/in_process_vehicle.hpp): the vehicle node's own control step
/// (vehicles' VehicleCoreOf) over the adapter its kind's factory opens,
/// without DDS or a thread. Here, in the programs' folder, because the
/// mediator and the vehicles' nodes never link each other.
#include <memory>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/mediator/in_process_vehicle.hpp"

namespace haptel::app {

/// The robot `vehicle` describes, on `track` (kept by reference). Throws
/// ConfigError when its kind does not step in process
/// (VehicleKindInfo::steps_in_process) or has no factory.
std::unique_ptr<mediator::InProcessRobot> MakeInProcessRobot(const VehicleConfig& vehicle,
                                                             const Track& track);

/// Registers MakeInProcessRobot with the mediator (SetInProcessRobotFactory).
void RegisterInProcessRobot();

}  // namespace haptel::app
