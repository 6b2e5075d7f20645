#pragma once
/// @file `haptel bench passivity`: time-domain passivity control against
/// device delay and stiffness, in four modes: off; `one-port`, the servo
/// loop's controller (haptel/haptics/passivity.hpp); `two-port`, an observer
/// at each end of the delay line exchanging energies with the samples and a
/// controller damping the arm on its side of the line
/// (haptel/haptics/twoport.hpp; the loop's end charges its own deficit to
/// the arm's); `two-port-ref`, the same with the credit bounded at zero.
///
/// The sim device's right arm (haptics/sim_device), behind a delay line of
/// 0, 1, 3 and 5 ms each way (readings reach the loop, and commands the arm,
/// that much later), is pressed by a light grip (muscle 250 N/m, 2 N·s/m, no
/// integral: the worst case for stability, a hand that adds little damping)
/// from 5 cm out to 1 cm beyond a virtual wall. The wall is a proxy kept out
/// of it — the coupling target is the tracked wrist projected onto the wall's
/// surface, re-computed before every tick as the physics thread would — and
/// the coupling stiffness K doubles from 250 N/m, with no coupling damping,
/// the loop at 1 kHz, the device file's safety (7 N, 2000 N/s, 0.5 s soft
/// start), stepped tick by tick in simulated time (deterministic).
///
/// Stable: no NaN and the contact settles — over the last 0.5 s of 3 s the
/// arm's true position moves less than 0.5 mm peak to peak (a growing or
/// sustained oscillation, held bounded only by the 7 N force limit, does
/// not). The largest stable K is the largest before the first unstable one,
/// per delay and mode; `gain` is the best mode's over off's at 3 ms (its
/// name in `gain_mode`; `gain_on`, `gain_two_port`… each mode's), beside
/// the passivity bound 2b/T (b the arm's own damping). Also per point: the
/// energy the controller dissipated (J), and the transparency: the RMS error
/// (N) of the force the arm felt against the ideal wall K·penetration of its
/// true position, over the contact (after 0.5 s). The cost: the servo tick's
/// time p99 with the controller on minus off, measured on the loop's own
/// Tick over the same runs.
///
/// The servo loop's own timing against the bare loop (bare_loop.hpp), in the
/// same run, after the sweep: the device file's loop threaded at its rate
/// and scheduling (servo_bench.hpp's MeasureServoLoop) with the controller
/// off and on, and the empty loop, 3 rounds of 3 s in a rotated order.
/// "Unchanged": on's period p99 (median over the rounds) within off's ± the
/// bare loop's own p99 spread over the rounds, at least one histogram bin.
///
/// Prints a table; writes build/bench/passivity.csv and passivity.png; with
/// --json the last stdout line is {"stable_stiffness_off":…,
/// "stable_stiffness_on":… (one-port),"stable_stiffness_two_port":…,
/// "stable_stiffness_two_port_ref":…,"gain":…,"gain_mode":…,
/// "passivity_bound":…,"cost_us_p99":… (the best mode's),
/// "force_rms_err_n_<mode>":… (mean over the K stable off and in the mode),
/// "force_rms_err_n_at_stable_<mode>":…,"servo_p99_us_bare":…,
/// "servo_p99_us_off":…,"servo_p99_us_on":…,"servo_p99_spread_us_bare":…,
/// "servo_p99_tolerance_us":…,"servo_p99_unchanged":…,
/// "servo_allocations_on":…,"servo_realtime":…,"delays":[…],"points":[{stiffness,
/// delay_ms,mode,stable,energy_j,force_rms_err_n},…]}.
///
/// --smoke (smoke.hpp): delays 0 and 3 ms, K up to 1000 N/m, 1.5 s runs;
/// the loop's timing in 2 rounds of 0.3 s.
namespace haptel::bench {

/// `haptel bench passivity [--device FILE] [--smoke] [--json]`; argv[0] is the
/// sub-command's name. Returns 0 when it ran, 2 for bad usage or configuration.
int BenchPassivityMain(int argc, const char* const* argv);

}  // namespace haptel::bench
