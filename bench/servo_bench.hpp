#pragma once
/// @file `haptel bench servo`: servo loop rate and period distribution for a
/// local one-arm sim, two sim arms in two-sided mode, and two arms served by
/// two haptel-device-server processes over UDP loopback with glove decimation
/// on and off. Table on stdout; CSV and a PNG of the period histograms under
/// build/bench/; with --json one JSON line at the end.
///
/// `haptel bench servo [--seconds S] [--device FILE] [--smoke] [--json]`;
/// --smoke (smoke.hpp): every mode for 0.5 s.
namespace haptel::bench {

int BenchServoMain(int argc, const char* const* argv);

}  // namespace haptel::bench
