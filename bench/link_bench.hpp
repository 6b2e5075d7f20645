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
///   p50/p95 against the truth (where the vehicle really was, in the map's
///   frame: prediction_score.hpp; p95 in the world's beside it) and p95
///   against each state's pose, the localised pose's p95 (both frames), the estimate's convergence
///   time and each estimated parameter beside its truth, and the true path's gap to the twin's (the
///   same lap in `none`: mean and largest distance between the two true paths, from the vehicles'
///   truth records). Then the targets on the robot's laps: lab at 400 ms, learning,
///   within 1.3x the 0 ms lap and error p95 within 5 cm; harsh completed and
///   learning's error below the nominal model's at every delay; none's error
///   ~0. With --link-profile NAME every lap runs on that link
///   (config/links/), its delay and loss replaced by the sweep's (its rate,
///   queue and jitter kept).
/// - Over seeds: --seeds 1-5 (a list of seeds and ranges, "1,3,7-9") drives
///   every lap once per seed of the reality's draws (`haptel run
///   --reality-seed`), and then reports each cell (vehicle, reality,
///   prediction, delay, loss) over the seeds: completed laps, the lap's and
///   the error's mean, standard deviation and the mean's 95 % interval
///   (Student's t, n − 1 degrees of freedom), and learning against the
///   nominal model seed by seed: the paired difference learn − nominal of
///   the lap and the error p95, its mean and 95 % interval, "better" or
///   "worse" only when the interval excludes 0. One seed's lap is one draw
///   of the reality and one lap's chances; a paired difference over seeds
///   is what a claim rests on. The harsh target is then judged on those
///   intervals (every cell better).
/// - --simulated-time: the robot's laps run `haptel run --simulated-time`
///   (the robot stepped in the run's process on one simulated clock, the
///   link its delay alone: no loss, no --link-profile, no blimp): a grand
///   prix lap in a second or two of CPU instead of 80 s of wall time, and
///   the same lap for the same seed to the tick.
///
/// Prints the tables; writes build/bench/link_rtt.csv, link_laps.csv,
/// link_estimates.csv, link_laps.png and link_laps_error.png (the blimp's:
/// link_laps_blimp*.png), and each lap's truth record in link_truth/; with --json the last stdout
/// line is
/// {"rtt":{…},"laps":[…],"seeds":[…],"simulated_time":…,"cells":[…],
/// "learn_minus_nominal":[…],"targets":{…}}.
///
/// DDS domains: the round trips on --domain D (default 200 + pid % 30), the
/// laps on --lap-domain (default D + 1).
/// --smoke (smoke.hpp): 2 s per round trip (1 s of it warm-up), one learning
/// lap of config/tracks/test-short.yaml in the `none` reality (the twin's:
/// the quickest lap) without delay or loss.
namespace haptel::bench {

/// `haptel bench link [--seconds S] [--vehicles robot,blimp] [--track FILE] [--blimp-track FILE]
/// [--reality LIST] [--seeds LIST] [--delays LIST] [--losses LIST] [--predict LIST]
/// [--link-profile NAME] [--simulated-time] [--domain D] [--lap-domain D] [--rtt-only] [--smoke]
/// [--json]`.
/// Returns 0 when every lap ran and the round trip was measured, 1 when one
/// could not be, 2 for bad usage.
int BenchLinkMain(int argc, const char* const* argv);

}  // namespace haptel::bench
