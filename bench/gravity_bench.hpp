#pragma once
/// @file `haptel bench gravity`: gravity compensation on the simulated arm.
///
/// Samples a grid over the box (the sim workspace shrunk by 5 cm on every
/// side, 5×5×5 vertices unless --counts), then releases the arm at N random
/// points in the box, once with compensation off (zero force) and once on
/// (grid force, commanded through the calibration as the servo loop does), and
/// measures how fast it drifts during 1 s of simulated time.
///
/// Drift speed = |true position after 1 s − true position at release| / 1 s,
/// from the simulator's true (unquantised) position. With compensation off
/// the arm falls until it hits the workspace floor, so the off figure is
/// bounded by the room below each point. drift_ratio = mean off / mean on,
/// with mean on floored at one encoder step per second (what the tracker can
/// still resolve; 1 µm/s if the encoder is not quantised): a compensated arm
/// often does not move at all, and a ratio with 0 below means nothing. The
/// JSON says when the floor was used and how many points did not move.
///
/// Prints a table; writes build/bench/gravity.csv (per point),
/// build/bench/gravity_vertices.csv (per vertex), build/bench/gravity.png
/// (drift per point, off and on) and the sampled grid
/// (build/bench/gravity_grid.yaml or --grid-out); with --json the last stdout
/// line is one JSON object.
///
/// --smoke (smoke.hpp): a 2×2×2 grid and 3 release points.
#include <cstdint>

#include "haptel/config/calibration.hpp"
#include "haptel/gravity/gravity_sampler.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/testing/gravity_on_sim.hpp"

namespace haptel::bench {

/// The hidden truth of a simulated arm as a calibration: what a perfect
/// `haptel calibrate` would have found.
ArmCalibration SimTruthCalibration(const haptics::SimDevice& device, haptics::Side side);

/// Places the arm at rest at `start` (true metres), commands the compensation
/// force for where the tracker says it is (zero when `grid` is null), lets go
/// of it and runs `seconds` of simulated time in 1 ms ticks from now_ns
/// (advanced), commanding the grid force through `calibration` every tick.
/// Returns the drift speed, m/s: distance between the true positions at
/// release and at the end, divided by `seconds`.
double MeasureDrift(haptics::SimDevice& device, haptics::Side side,
                    const ArmCalibration& calibration, const haptics::GravityGrid* grid,
                    const haptics::Vec3d& start, double seconds, int64_t& now_ns);

/// `haptel bench gravity [--device FILE] [--points N] [--seed S] [--counts N]
/// [--grid-out FILE] [--smoke] [--json]`; argv[0] is the sub-command's name.
/// Returns 0, 1 when sampling failed, 2 for bad usage or configuration.
int BenchGravityMain(int argc, const char* const* argv);

}  // namespace haptel::bench
