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
/// - The lap against the network: `haptel run --link-fault delay=D,loss=L`
///   with the automatic operator on --track (default the grand prix) for each
///   delay (--delays, ms, default 0,50,100,200,400,800) and loss (--losses,
///   %, default 0,5), without and with the predictive display (--predict
///   off|on|both, default both): lap time and its ratio to the 0 ms lap,
///   obstacles touched, completion, measured round trip, the predictor's
///   error p95. Each end delays what it receives by D, so the round trip is 2D.
///   With --link-profile NAME every lap runs on that link (config/links/),
///   its delay and loss replaced by the sweep's (its rate, queue and jitter
///   kept).
///
/// Prints both tables; writes build/bench/link_rtt.csv, link_laps.csv and
/// link_laps.png; with --json the last stdout line is
/// {"rtt":{…},"laps":[…]}.
///
/// DDS domains: the round trips on --domain D (default 200 + pid % 30), the
/// laps on --lap-domain (default D + 1).
/// --smoke (smoke.hpp): 2 s per round trip (1 s of it warm-up), one lap of
/// config/tracks/test-short.yaml without delay or loss, with prediction.
namespace haptel::bench {

/// `haptel bench link [--seconds S] [--track FILE] [--delays LIST] [--losses LIST]
/// [--predict off|on|both] [--link-profile NAME] [--domain D] [--lap-domain D] [--smoke] [--json]`.
/// Returns 0 when every lap ran and the round trip was measured, 1 when one
/// could not be, 2 for bad usage.
int BenchLinkMain(int argc, const char* const* argv);

}  // namespace haptel::bench
