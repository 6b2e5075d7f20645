#pragma once
/// @file `haptel bench hands`: the mouse device as every interface's hands
/// (issue 36), driven through the real SDL window under an Xvfb of the
/// bench's own by the real X pointer (XTest, testing/x_desktop.hpp).
///
/// Per interface (--interfaces, default gesture, gesture-shared, cockpit,
/// cockpit-assisted), two runs of `haptel run --operator person --device
/// <mouse> --view window` on the short track with one obstacle put 0.35 m
/// ahead of the start (so every interface meets a contact):
/// 1. engaged (the button held), one scripted pointer path, the same for
///    every interface: --steps steps of ±100 px up and down from the
///    window's centre, 0.6 s apart; then the pointer held up (forward)
///    until the bumper touches; held still 1 s; pushed a further 60 px up
///    (across the wall) and 60 px right (along it). The run's device trace
///    (--trace) gives the hands; the command topic gives the commands.
///    Reported: the commands (their count, the largest forward and turn);
///    input-to-command p50/p95 (a pointer step sent through XTest to the
///    first command after it that differs from the one before it; target
///    ≤ 20 ms); the pointer hand's displacement over the cursor's (the
///    pseudo-haptic ratio: free, across the wall, along it); contact to
///    the hands' first motion of 1 mm with the pointer still (its shake or
///    push-back); the servo loop's p99 (the run's) against an empty loop at
///    its rate (bare_loop.hpp) beside the run and alone.
/// 2. nobody engaged: the same path with no button for --nobody-s
///    (default 60 s): the commands that would move the vehicle (either
///    tread non-zero; target 0) and the distance it went.
///
/// Prints a table; writes build/bench/hands.csv and hands.png (the pointer
/// hand's forward offset against the cursor's over the engaged path, per
/// interface); --json ends with one line.
///
/// --smoke (smoke.hpp): gesture only, 4 steps, a 5 s bound on the contact,
/// 3 s with nobody engaged, the bare loop 0.5 s.
namespace haptel::bench {

/// `haptel bench hands [--interfaces LIST] [--device FILE] [--steps N]
/// [--nobody-s S] [--domain D] [--smoke] [--json]`. Returns 0 when every run
/// gave its figures, 1 when one did not, 2 for bad usage.
int BenchHandsMain(int argc, const char* const* argv);

}  // namespace haptel::bench
