#pragma once
/// @file `haptel bench record`: what recording a whole run costs (issue 37).
///
/// Two laps of the grand prix (config/tracks/grand-prix.yaml) by the
/// automatic operator with the operator's view drawn offscreen, one run
/// after the other in this process (RunSession, the vehicle spawned as
/// `haptel run` spawns it): without a session file, then with one. From
/// them: the recorder thread's CPU share of a core (its CPU time over the
/// run's wall time; target ≤ 3 %), the bytes per minute of each channel, the
/// messages dropped (target 0), and the servo loop's period p99 of both runs
/// against the bare loop's (bare_loop.hpp, measured alone beside them;
/// target: unchanged). Then the session file's seek on a synthetic one-hour
/// file (mcap_seek.hpp: open, and a second read at random seconds; target
/// < 100 ms).
///
/// Prints a table; writes build/bench/record.csv (one row per channel);
/// --json ends with one line.
///
/// --smoke (smoke.hpp): 4 s of the short track each, a 60 s synthetic file,
/// 10 seeks, the bare loop 0.5 s.
namespace haptel::bench {

/// `haptel bench record [--track FILE] [--hours H] [--domain D] [--smoke]
/// [--json]`. Returns 0 when both runs gave their figures, 1 when one did
/// not, 2 for bad usage.
int BenchRecordMain(int argc, const char* const* argv);

}  // namespace haptel::bench
