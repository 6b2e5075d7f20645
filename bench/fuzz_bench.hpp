#pragma once
/// @file `haptel bench fuzz`: every parser in the product fed mutated and
/// random input; nothing may crash or hang, everything must end in a value
/// or a clear error.
///
/// Targets (each a parser a stranger's bytes reach):
/// - config: every shipped YAML file (runs, tracks, courses, vehicles,
///   devices, interfaces, physics, studies), mutated, through the loader that
///   reads it (found by which loader takes the unmutated file);
/// - scene: the scene files, YAML and the thesis's MHaptic XML (LoadSceneFile);
/// - udp: datagrams of the haptic device protocol (udp::Decode);
/// - servo: byte streams into the simulated Maestro and SC-8000 (the
///   device's decoder), and controller replies into the real adapter's
///   ServoOutput;
/// - can: CAN frames into the ODrive decoders, and candump text lines;
/// - dds: serialized TreadCommand, BlimpCommand, VehicleState and
///   BlimpState payloads, mutated, through Fast DDS's CDR deserializer and
///   then the vehicle's range checks (NaN, infinities, out of range);
/// - console: HTTP requests (every route, forms with their token, chunked
///   bodies) to the experimenter's console served for real on loopback.
///
/// Mutations (seeded, repeatable): bit flips, byte insertions, deletions
/// and duplications of chunks, interesting values ("nan", "-1e308", "[{",
/// 0xFF...), splices between seeds. An input that throws something other
/// than std::exception, or takes longer than 5 s, stops the run and is
/// written to build/bench/fuzz-<target>-<kind>.bin; a crash writes it from
/// the signal handler before the process dies.
#include <cstdint>
#include <string>
#include <vector>

namespace haptel::bench {

struct FuzzResult {
  std::string target;
  uint64_t inputs = 0;
  uint64_t accepted = 0;  ///< parsed into a value
  uint64_t rejected = 0;  ///< a clear error (an exception, a status, a dropped frame)
  double seconds = 0.0;
  double slowest_ms = 0.0;  ///< the slowest single input
  /// The console only: the slowest of a few page requests (GET /) made while
  /// 100 slow connections (40 from the same address, 60 from 20 others)
  /// dribble partial requests or send nothing; negative for other targets.
  double page_under_slow_clients_ms = -1.0;
};

/// The target names, in order.
std::vector<std::string> FuzzTargets();
/// Fuzzes `target` with `inputs` inputs from `seed`; throws
/// std::invalid_argument for an unknown target. Crashes and hangs end the
/// process (see the file comment).
FuzzResult Fuzz(const std::string& target, uint64_t inputs, uint64_t seed);

/// `haptel bench fuzz [--inputs N] [--target NAME] [--seed S] [--smoke] [--json]`;
/// --smoke (smoke.hpp): 300 inputs per target.
int BenchFuzzMain(int argc, const char* const* argv);

}  // namespace haptel::bench
