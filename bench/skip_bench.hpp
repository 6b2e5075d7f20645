#pragma once
/// @file `haptel bench skip`: what physics costs per simulated second, and
/// that what the scene does not need costs nothing (DESIGN.md, "Skip what the
/// scene does not need").
///
/// Configurations, each stepped for --seconds of simulated time (default 2) at
/// the configured step (config/physics.yaml or --physics), after a warm-up of
/// 2.5 simulated seconds (untimed: Bullet puts a body to sleep after 2 s at
/// rest):
/// - gesture: no physical controls, no scene bodies → NeedsWorld is false, no
///   world is created, nothing is stepped: 0.
/// - cockpit: the cockpit interface's world — both proxy hands and the wheel
///   and throttle bodies (physics::CockpitControlsBody, built from the shipped
///   config/interfaces/cockpit.yaml). The right palm rests on the top of the
///   rim (3 mm into it) and turns the wheel ±0.2 rad at 0.5 Hz; the left hand
///   hovers 3 cm over the throttle knob, moving 2 cm at 0.5 Hz.
/// - cockpit_sleeping_N (N = 0, 100, 1000): the cockpit plus a floor 0.4 m
///   below the hub and N dynamic 10 cm boxes resting on it outside the
///   cockpit's footprint (seeded jittered grid, random yaw), asleep once the
///   warm-up is over.
/// - cockpit_static_1000 (table, CSV, and the JSON's cpu_per_sim_s_static_1000):
///   the same 1000 boxes made static, for comparison.
///
/// Figure: thread CPU time (CLOCK_THREAD_CPUTIME_ID) around the stepping, per
/// simulated second, i.e. the share of one core the physics thread needs; and
/// in the table the ratio of each world to cockpit_sleeping_0 from the same run.
///
/// Also, for the vehicle side: what its camera loop costs with the synthetic
/// camera of the shipped config/vehicles/sim-robot.yaml (its size and rate;
/// 640x480 at 30 fps) and at 320x240 — thread CPU per frame of the render
/// (CameraSource::Grab) and of the JPEG encode, the wall time of both, and the
/// share of one core that is at camera.rate_hz (build/bench/skip_camera.csv).
///
/// Prints a table; writes build/bench/skip.csv; with --json the last stdout
/// line is {"cpu_per_sim_s":{"gesture":0,"cockpit":…,…},"cpu_per_sim_s_static_1000":…,
/// "video_decode_cpu_share":{…},"vehicle_camera":{"width":640,…,"cpu_share":…}}.
///
/// --smoke (smoke.hpp): every world, decode and camera for 0.2 s (after the
/// same warm-up: the boxes must fall asleep), with 10 and 100 floor boxes
/// instead of 100 and 1000 (cockpit_sleeping_10, _100, cockpit_static_100).
namespace haptel::bench {

/// `haptel bench skip [--physics FILE] [--seconds S] [--smoke] [--json]`; argv[0] is the
/// sub-command's name. Returns 0, or 2 for bad usage or configuration.
int BenchSkipMain(int argc, const char* const* argv);

}  // namespace haptel::bench
