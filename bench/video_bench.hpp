#pragma once
/// @file `haptel bench video`, part 1: the link's video codecs, run time
/// against error (issue 24).
///
/// The synthetic camera's frames (the vehicle file's camera: 640x480 at
/// 30 fps as shipped) driven along the grand prix's centre line at the
/// robot's top speed, in 4 clips of 2.5 s spread evenly round the lap, are
/// encoded and decoded by JPEG at qualities 20..95 and by H.264 (the link's
/// latency-tuned libx264: video::H264Encoder) at 0.25..8 Mbit/s. Per point:
/// the bitrate (encoded bytes over the clips' duration), SSIM and PSNR of each
/// decoded picture against its source frame (means), and the thread CPU ms
/// per frame of the encode and of the decode. The Pareto front is over
/// (bitrate, SSIM): a point is on it when no other has a lower bitrate and a
/// higher SSIM. The vehicle file's codec and setting (camera.codec with
/// jpeg_quality or bitrate_kbps) is measured too and its place on the front
/// said.
///
/// Prints a table; writes build/bench/video_codecs.csv and video_codecs.png
/// (bitrate against SSIM, both codecs, the front marked); with --json the
/// last stdout line is {"codecs":[{"codec","setting","bitrate_kbps","ssim",
/// "psnr_db","encode_ms","decode_ms","pareto"}...],"default":{"codec",
/// "setting","on_pareto_front"}}; `setting` is the JPEG quality or the
/// H.264 target in kbit/s.
///
/// --smoke (smoke.hpp): one clip of 15 frames, JPEG at 20 and 80, H.264 at
/// 250 and 2000 kbit/s, and the default.
namespace haptel::bench {

/// `haptel bench video [--vehicle FILE] [--track FILE] [--smoke] [--json]`;
/// argv[0] is the sub-command's name. Returns 0, or 2 for bad usage or
/// configuration.
int BenchVideoMain(int argc, const char* const* argv);

}  // namespace haptel::bench
