#pragma once
/// @file `haptel bench servo`: servo loop rate and period distribution for a
/// local one-arm sim, two sim arms in two-sided mode, and two arms served by
/// two haptel-device-server processes over UDP loopback with glove decimation
/// on and off. Table on stdout; CSV and a PNG of the period histograms under
/// build/bench/; with --json one JSON line at the end.
///
/// `haptel bench servo [--seconds S] [--device FILE] [--smoke] [--json]`;
/// --smoke (smoke.hpp): every mode for 0.5 s.
#include <cstdint>
#include <vector>

#include "haptel/config/device.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::bench {

/// What one servo loop measured about itself over a run.
struct ServoLoopRun {
  LoopStats stats;
  uint64_t allocations = 0;  ///< heap allocations anywhere in the process while it ran
  bool memory_locked = false;
  std::vector<double> histogram;  ///< period counts per bin (LoopMeter's 10 µs bins)
};

/// Runs `device` under a threaded servo loop built from `config` (its rate,
/// scheduling, passivity…) for `seconds` after a 0.2 s start, feeding a fresh
/// spring field every 10 ms as an interface would, so forces are computed
/// each tick. Also what `haptel bench passivity` times the loop with.
ServoLoopRun MeasureServoLoop(haptics::Device& device, const DeviceConfig& config, double seconds);

int BenchServoMain(int argc, const char* const* argv);

}  // namespace haptel::bench
