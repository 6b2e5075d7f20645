#pragma once
/// @file `haptel bench fleet`: what each vehicle of a fleet costs one
/// operator's station (issue 30).
///
/// Runs `haptel run --fleet` (the automatic operator, no view; each vehicle
/// a haptel-vehicle process of its own over DDS) on the first 1, 2, … N
/// vehicles of --fleet (default config/fleets/four.yaml: three robots, then
/// the blimp), each count to the end of every course, and reports per count:
/// - the handovers (switch request to the new vehicle obeying a command
///   sent after its lock was released) p50/p95, ms; the fleet file's
///   slice_s makes the automatic operator switch often (target: p95 ≤
///   300 ms at 4 vehicles, with ≥ 20 handovers);
/// - the operator process's CPU share (CPU seconds per wall second, all its
///   threads) and what each vehicle added costs over the count before;
/// - the servo loop's period p99 over the run, and over the ticks that
///   played the switch cue alone, against an empty clock_nanosleep loop at
///   the same rate and priority (bare_loop.hpp) measured in this process
///   twice per count: alone before the run, and beside it (the same load).
///
/// "Unchanged", defined before measuring: the servo loop's p99 (over the
/// run, and over the cue's ticks) is no more than the largest p99 the bare
/// loop showed in this bench run (its run-to-run spread on this machine)
/// plus one 10 µs histogram bin.
///
/// Then the video (fleet_video.hpp, issue 40), per count: N vehicles
/// streaming the lap on loopback into this process's receivers and a view
/// (a window on $DISPLAY, offscreen without one), the first driven, the
/// others tiles asking for previews (--full-tiles: not, the figure before);
/// per vehicle its kbit/s, rate estimate (last, least), cuts, pictures per
/// second, size and SSIM. Targets at 3 vehicles: the driven video within
/// 20 % of a single vehicle's, SSIM >= 0.95, no estimate under 300 kbit/s.
/// --video-only skips the runs above; --video-seconds sets the measurement.
///
/// Prints a table; writes build/bench/fleet.csv and fleet.png (operator CPU
/// and handover p95 against the vehicle count) and fleet_video.csv; with
/// --json the last stdout line is {"counts":[…],"handover_ms_p95_at_4":…,
/// "servo_p99_us_bare":…,"servo_p99_us_fleet":…,…,"video":{"counts":[…],
/// "driven_kbps_ratio_3_to_1":…,"driven_ssim_at_3":…,"target_kbps_least":…,
/// "target_met":…}}.
///
/// --smoke (smoke.hpp): the counts 1 and N only, each cut at 6 s
/// (--time-limit) with a 1 s slice, the bare loop for 0.5 s; the video 3 s
/// per count after a 1 s warm-up.
namespace haptel::bench {

/// `haptel bench fleet [--fleet FILE] [--counts LIST] [--slice S] [--time-limit S]
/// [--device FILE] [--domain D] [--video-seconds S] [--video-only] [--full-tiles] [--smoke]
/// [--json]`. Returns 0 when every count
/// ran and gave its figures, 1 when one did not, 2 for bad usage.
int BenchFleetMain(int argc, const char* const* argv);

}  // namespace haptel::bench
