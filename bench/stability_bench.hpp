#pragma once
/// @file `haptel bench stability`: stress tests of the physics world that must
/// end without NaN (no hand or body reset) and within bounds.
///
/// - stiffness: per step size T ∈ {0.25, 0.5, 1, 2, 4} ms, the proxy palm
///   (hand gravity off, world without contacts) coupled to a tracked wrist
///   that jumps 2 cm, then holds while a 1 N force pushes the palm (measured
///   stiffness K_eff = 1 N / offset), then holds free. The linear coupling
///   stiffness K doubles from 1e2 up to a cap (~1.3e7) with the damping fixed
///   at the configured b, until the palm diverges (reset, error > 10 cm, or
///   the palm's energy growing while held). Reported per T: the largest
///   stable K, the passivity bound K_passive = 2b/T, Bullet's spring clamp
///   m/(16T²) and the K at which the proxy hand switches to its implicit
///   soft lock (proxy_hand.cpp): what actually keeps it stable.
/// - mass_ratio: a 9 g capsule (the distal phalanx) on a box of 10·, 100·,
///   1000· its mass and a 10 kg box, 2.5 s resting then 2.5 s pressed down
///   with 5 N; max penetration of the capsule into the box (Bullet's contact
///   distance).
/// - squash: two proxy palms on a 0.5 kg box, tracked wrists moving inward so
///   the coupling force K·depth rises from 0 through the device limit (7 N)
///   to 50 N; max box speed and palm/box penetration; the box must stay
///   between the palms.
/// - grasp_release: 10 simulated minutes (--minutes) of close, lift 10 cm,
///   open, drop, settle; total mechanical energy of the dynamic bodies at the
///   start of each cycle (at rest), drift last − first and max excursion.
///   At 1 ms when a 5 s probe projects ≤ 60 s of wall time, else at 2 ms.
///
/// Prints a table per test; writes build/bench/stability_*.csv and
/// stability_stiffness.png; with --json the last stdout line is
/// {"passed":…,"tests":{"stiffness":{…},"mass_ratio":{…},"squash":{…},"grasp_release":{…}}}.
///
/// --smoke (smoke.hpp): the stiffness sweep at T = 1 and 4 ms only, and two
/// grasp_release cycles (8 s); mass_ratio and squash as in the full run.
namespace haptel::bench {

/// `haptel bench stability [--physics FILE] [--minutes M] [--smoke] [--json]`; argv[0]
/// is the sub-command's name. Returns 0 when every test passed, 1 when one
/// failed, 2 for bad usage or configuration.
int BenchStabilityMain(int argc, const char* const* argv);

}  // namespace haptel::bench
