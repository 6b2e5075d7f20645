#pragma once
/// @file `haptel bench physics`: a work-precision diagram of the physics
/// world — what the fixed step, the solver's iteration count and Bullet's
/// precision (double, or float through haptel-physics-bench-float) buy in
/// accuracy, and what they cost in CPU.
///
/// Grid: steps {0.25, 0.5, 1, 2, 4, 8} ms × iterations {5, 10, 20} × {double,
/// float}. Per point (physics_measure.hpp):
/// - tracking_err_mm: RMS distance between the proxy wrist following a
///   recorded hand trajectory (build/bench/trajectory.csv: deterministic,
///   synthetic, sums of sines, 0.3 m/s peak, 2 s, 4 kHz; written when missing
///   and read back) and the same proxy in a reference run: double precision,
///   one step of 0.025 ms (a tenth of the finest step, so ≥ 10× finer than
///   every point), 40 iterations, at every sample time the point has.
/// - penetration_mm: the palm comes down on a table at 0.1 m/s and is pushed
///   into it with 10 N (tracked wrist 10 N / k below the surface), 1 s: the
///   deepest penetration (at rest Bullet leaves ~0; the CSV has that too).
/// - slip_mm: a 0.5 kg box squeezed between two palms, lifted 10 cm in 1 s,
///   then held 5 s: how far it moved relative to the palms' midpoint in the hold.
/// - cpu_per_sim_s: thread CPU time (CLOCK_THREAD_CPUTIME_ID) around the
///   SetTracked + Step calls of all three scenarios, per simulated second.
///
/// Pareto front over (cpu_per_sim_s, tracking_err_mm), both precisions; the
/// default (config/physics.yaml or --physics: step and iterations, double) is
/// placed on it: on the front, or by how much the front beats it (error ratio
/// at no more CPU, CPU ratio at no more error).
///
/// The float points come from a child, haptel-physics-bench-float (next to
/// this executable, physics sources built against float Bullet), run on the
/// other core while this process measures double; without it the points are
/// double only and the output says so.
///
/// Prints a sorted table; writes build/bench/physics.csv and
/// build/bench/physics_pareto.png; with --json the last stdout line is
/// {"points":[…],"default":{…},…}.
///
/// --smoke (smoke.hpp): steps {1, 8} ms × iterations {5, 20}, both
/// precisions, a 0.5 s trajectory, a 0.6 s push and a 1 s hold, against the
/// same 0.025 ms reference (wp::SmokePlan).
namespace haptel::bench {

/// `haptel bench physics [--physics FILE] [--no-float] [--smoke] [--json]`; argv[0] is
/// the sub-command's name. Returns 0, 1 when a measurement fails, 2 for bad usage.
int BenchPhysicsMain(int argc, const char* const* argv);

}  // namespace haptel::bench
