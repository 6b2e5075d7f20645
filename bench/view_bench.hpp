#pragma once
/// @file `haptel bench view`: what the operator's view costs and how fresh
/// the video it shows is, with the servo loop measured beside it.
///
/// Phases, each measured for --seconds (default 5) after a 1 s warm-up, all
/// with the real parts: the sim device's servo loop (HapticSide), a physics
/// world with both proxy hands and the HUD cockpit's wheel and lever
/// (SessionPhysics), a spawned haptel-vehicle streaming 640×480 JPEG at
/// 30 fps over DDS (VehicleLink), and the view (SessionView: the session's
/// own Fill, overlay and renderer), in a window when $DISPLAY is reachable
/// (run it under xvfb-run) and offscreen otherwise:
/// - bare: an empty clock_nanosleep loop (PeriodicThread) at the servo rate
///   and priority, nothing else running: the baseline period p99.
/// - world: servo + physics + vehicle link, video not decoded, no view.
/// - view: the same with the view drawing at 60 Hz (video decoded).
/// - view+mp4: the same, recording the view to H.264 MP4 at 30 fps.
///
/// Figures: view frames per second and frame time p50/p99 (render + swap);
/// the view thread's CPU share, and the process CPU the view adds over
/// `world` (decoding, rendering, Mesa's own threads: the honest cost);
/// capture-to-screen latency (vehicle capture stamp → the swap that first
/// showed the frame) p50/p99; servo period p99 in each phase and its ratio to
/// bare (`servo_p99_ratio_to_bare`, the view phase).
///
/// Prints a table; writes build/bench/view.csv and view.png (servo period
/// distributions); with --json the last stdout line holds the figures.
///
/// --domain D puts the vehicle on DDS domain D (default 150 + pid % 80).
/// --smoke (smoke.hpp): every phase for 0.5 s after a 0.25 s warm-up.
namespace haptel::bench {

/// `haptel bench view [--seconds S] [--domain D] [--smoke] [--json]`; argv[0]
/// is the sub-command's name. Returns 0, 1 when a part fails, 2 for bad usage.
int BenchViewMain(int argc, const char* const* argv);

}  // namespace haptel::bench
