#pragma once
/// @file The gravity sampler run on the simulated device, in simulated time:
/// for the gravity tests and `haptel bench gravity`. It is `haptel calibrate
/// --gravity --auto`'s procedure (SampleGravity), its log discarded; a real
/// device is sampled by the same procedure with a person placing the arm.
#include <cstdint>

#include "haptel/gravity/gravity_sampler.hpp"
#include "haptel/haptics/sim_device.hpp"

namespace haptel::haptics {

/// Samples a grid on a simulated device in simulated time (1 ms ticks from
/// start_ns): each vertex is reached with SimDevice::Place and then
/// SimDevice::Release, so only the device force holds the arm. Measures the
/// wall time too. Leaves the device with zero force commanded.
GravitySampleReport SampleGravityOnSim(SimDevice& device, Side side,
                                       const ArmCalibration& calibration,
                                       const GravitySamplerConfig& config,
                                       int64_t start_ns = 1'000'000);

}  // namespace haptel::haptics
