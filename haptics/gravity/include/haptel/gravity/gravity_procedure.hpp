#pragma once
/// @file `haptel calibrate --gravity`: a device's gravity grid, sampled by
/// the GravitySampler ticked at the device's servo rate on the device's own
/// clock (DeviceTicker). Attended, a person brings the arm to each vertex,
/// presses Enter and lets go; the sampler then holds it horizontally and
/// nudges the vertical force until it holds still. Unattended (the sim
/// device only) its simulated operator does the same: places the arm at
/// the vertex and lets go (SimDevice::Place, Release), in simulated time.
#include <cstdint>
#include <iosfwd>

#include "haptel/gravity/gravity_sampler.hpp"

namespace haptel::haptics {

struct GravityProcedureOptions {
  bool auto_mode = false;        ///< unattended: the sim device's operator places the arm
  double rate_hz = 1000.0;       ///< ticks per second (the device file's servo.rate_hz)
  int64_t start_ns = 1'000'000;  ///< simulated time of the first tick (auto mode)
};

/// Samples the grid of `side` (`config.box_min`..`box_max`, `config.counts`)
/// on `device`, prompting on `log` and waiting for Enter on `in` at each
/// vertex when attended. The report says whether it converged everywhere
/// (`ok`, else `error` names the vertex) and how long it took (`wall_time_s`
/// measured). Leaves the arm with zero force commanded. std::invalid_argument
/// for auto mode on a device that is not simulated, a rate outside (0, 100]
/// kHz, or what GravitySampler refuses; std::runtime_error when the input
/// ends before the last vertex.
GravitySampleReport SampleGravity(Device& device, Side side, const ArmCalibration& calibration,
                                  const GravitySamplerConfig& config,
                                  const GravityProcedureOptions& options, std::ostream& log,
                                  std::istream& in);

}  // namespace haptel::haptics
