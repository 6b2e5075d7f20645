#pragma once
/// @file `haptel bench skip`: what physics costs per simulated second, and
/// that what the scene does not need costs nothing (DESIGN.md, "Skip what the
/// scene does not need").
///
/// Configurations, each stepped for --seconds of simulated time (default 2) at
/// the configured step (config/physics.yaml or --physics), after a warm-up of
/// 2.5 simulated seconds (untimed: Bullet puts a body to sleep after 2 s at
/// rest):
/// - gesture: no physical controls, no scene bodies → NeedsWorld is false, no
///   world is created, nothing is stepped: 0.
/// - cockpit: two proxy hands, tracked hovering above the table and moving
///   gently, and the shipped table scene (config/scenes/table.yaml). Without
///   the wheel and throttle bodies (physics/cockpit_controls.hpp): they sit in
///   the device frame around z = 0, inside the table scene's floor; the output
///   says so.
/// - cockpit_sleeping_N (N = 0, 100, 1000): the cockpit world plus N dynamic
///   10 cm boxes resting on the floor around the table (seeded jittered grid,
///   random yaw), asleep once the warm-up is over.
///
/// Figure: thread CPU time (CLOCK_THREAD_CPUTIME_ID) around the stepping, per
/// simulated second, i.e. the share of one core the physics thread needs; and
/// in the table the ratio of each world to cockpit_sleeping_0 from the same run.
///
/// Prints a table; writes build/bench/skip.csv; with --json the last stdout
/// line is {"cpu_per_sim_s":{"gesture":0,"cockpit":…,…}}.
namespace haptel::bench {

/// `haptel bench skip [--physics FILE] [--seconds S] [--json]`; argv[0] is the
/// sub-command's name. Returns 0, or 2 for bad usage or configuration.
int BenchSkipMain(int argc, const char* const* argv);

}  // namespace haptel::bench
