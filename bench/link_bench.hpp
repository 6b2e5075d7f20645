#pragma once
/// @file `haptel bench link`: what the DDS link costs and what a bad network
/// does to a lap.
///
/// - Round trip, in one run: a raw Fast DDS ping-pong (a TreadCommand echoed
///   at once by a second process, `haptel-bench link --echo`, on the same
///   transports: UDP and shared memory on loopback) against Haptel's own
///   command round trip to a spawned haptel-vehicle (the echo in its state,
///   its wait at the vehicle subtracted, as `haptel run` measures it). Both
///   at 100 Hz for --seconds. Target: Haptel's p50 within 2x of raw. Then
///   the cost of DDS Security: Haptel's round trip and video latency again
///   with the link authenticated and encrypted (build/bench/security, made
///   by `haptel security init` the first time).
/// - The lap against the network and the reality gap: `haptel run
///   --link-fault delay=D,loss=L --reality R --predict M` with the automatic
///   operator, for each vehicle (--vehicles, default robot,blimp: the robot
///   on --track, default the grand prix; the blimp on --blimp-track, default
///   the blimp hop, with config/blimp.yaml), reality (--reality, names of
///   config/realities/ or files, default none,lab,harsh: the vehicle's hidden
///   truth, which the operator side never reads), loss (--losses, %, default
///   0), prediction (--predict, a list of off, nominal — the vehicle's
///   nominal model only —, learn — the model with what it estimates while
///   driving; on = learn, both = off,learn, all = the three, the default) and
///   delay (--delays, ms each way, default 0,100,200,400; each end delays
///   what it receives by D, so the round trip is 2D). Per lap: outcome, lap
///   time and its ratio to the 0 ms lap (same vehicle, reality, loss and
///   prediction), obstacles, measured round trip, the prediction's error
///   p50/p95 against the truth (where the vehicle really was) and p95
///   against its own odometry, the estimate's convergence time and each
///   estimated parameter beside its truth, and the true path's gap to the
///   twin's (the same lap in `none`: mean and largest distance between the
///   two true paths, from the vehicles' truth records).
///   Then the targets on the robot's laps: lab at 400 ms, learning,
///   within 1.3x the 0 ms lap and error p95 within 5 cm; harsh completed and
///   learning's error below the nominal model's at every delay; none's error
///   ~0. With --link-profile NAME every lap runs on that link
///   (config/links/), its delay and loss replaced by the sweep's (its rate,
///   queue and jitter kept).
///
/// Prints the tables; writes build/bench/link_rtt.csv, link_laps.csv,
/// link_estimates.csv, link_laps.png and link_laps_error.png (the blimp's:
/// link_laps_blimp*.png), and each lap's truth record in link_truth/; with --json the last stdout
/// line is
/// {"rtt":{…},"laps":[…],"targets":{…}}.
///
/// DDS domains: the round trips on --domain D (default 200 + pid % 30), the
/// laps on --lap-domain (default D + 1).
/// --smoke (smoke.hpp): 2 s per round trip (1 s of it warm-up), one learning
/// lap of config/tracks/test-short.yaml in the `none` reality (the twin's:
/// the quickest lap) without delay or loss.
namespace haptel::bench {

/// `haptel bench link [--seconds S] [--vehicles robot,blimp] [--track FILE] [--blimp-track FILE]
/// [--reality LIST] [--delays LIST] [--losses LIST] [--predict LIST] [--link-profile NAME]
/// [--domain D] [--lap-domain D] [--rtt-only] [--smoke] [--json]`.
/// Returns 0 when every lap ran and the round trip was measured, 1 when one
/// could not be, 2 for bad usage.
int BenchLinkMain(int argc, const char* const* argv);

}  // namespace haptel::bench
