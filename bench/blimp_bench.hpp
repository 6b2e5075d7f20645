#pragma once
/// @file `haptel bench blimp`: the airship model's run time against its error.
///
/// - Work precision: a 60 s manoeuvre in gusty wind (ManoeuvreControls: all
///   five actuators, commands held per 0.1 s) flown by semi-implicit Euler,
///   explicit midpoint and RK4 at steps 0.1 … 1 ms; the error is the final
///   position's distance from RK4 at 0.25 ms, against the thread CPU time per
///   simulated second. The configured integrator and step must lie on the
///   Pareto front (no run both cheaper and more accurate). Any non-finite
///   state at any step fails the sweep.
/// - Physics checks (AirshipTrials): hover drift at neutral buoyancy, the top
///   speed (35 km/h ± 10 %), the rudder's yaw rate at 5 km/h under a tenth of
///   that at 20 km/h, and energy drift < 0.1 % over 10 simulated minutes with
///   drag and thrust off, for each integrator at the configured step.
///
/// Prints both tables; writes build/bench/blimp_precision.csv,
/// blimp_checks.csv and blimp_precision.png; with --json the last stdout line
/// is {"passed":…,"default":{…},"sweep":[…],"checks":{…}}.
///
/// --smoke (smoke.hpp): every row and check, on a 10 s manoeuvre flown once
/// per row and 60 s of energy drift. Its CPU figures are too short to place
/// the configured step on the front: it reports the place, and does not fail
/// on it.
namespace haptel::bench {

/// `haptel bench blimp [--vehicle FILE] [--smoke] [--json]`: FILE is a blimp vehicle
/// file (default config/vehicles/sim-blimp.yaml). Returns 0 when every check
/// passed, 1 when one failed, 2 for bad usage or configuration.
int BenchBlimpMain(int argc, const char* const* argv);

}  // namespace haptel::bench
