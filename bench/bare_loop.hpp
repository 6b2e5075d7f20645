#pragma once
/// @file The machine's own timing floor: an empty clock_nanosleep loop
/// (PeriodicThread, absolute deadlines) at a given rate and SCHED_FIFO
/// priority. Benchmarks report a loop's period p99 as a ratio to this one's,
/// measured in the same run: the machine's noise changes from run to run, the
/// ratio much less.
#include <functional>
#include <vector>

#include "haptel/core/loop_meter.hpp"

namespace haptel::bench {

struct BareLoop {
  LoopStats stats;
  std::vector<double> histogram;  ///< period counts per bin (LoopMeter's bins)
  double bin_us = 0.0;
};

/// Runs the empty loop for `seconds` (after a 0.2 s start) and returns its figures.
BareLoop MeasureBareLoop(double rate_hz, int realtime_priority, double seconds);

/// Runs the empty loop while `work` runs on the calling thread (another
/// process's run, say) and returns its figures: the machine's timing floor
/// under the same load.
BareLoop MeasureBareLoopWhile(double rate_hz, int realtime_priority,
                              const std::function<void()>& work);

}  // namespace haptel::bench
