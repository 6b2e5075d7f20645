#pragma once
/// @file The session file's "time to open and seek a one-hour file" (issue
/// 37), for `haptel bench record`: a synthetic recording at the channel rates
/// of a real run, then Reader::Open and reads at random seconds of it.
///
/// The synthetic file (WriteSyntheticSession): for `duration_s` of log time,
/// - /haptic at 1 kHz: both hands' tracked and proxy poses, forces, the
///   passivity energy and the servo period (200 bytes of slowly varying
///   doubles, as compressible as the real ones);
/// - /command and /state at 50 Hz (48 and 96 bytes);
/// - /video at 30 fps, ~2 KB frames of random bytes (H.264 does not compress
///   further); a key frame of 8 KB each second;
/// with the writer's defaults (zstd level 1, 1 MiB chunks) unless given.
///
/// MeasureSeek: the file's pages dropped from the page cache first (cold, as
/// a file opened a day later), the wall time of Reader::Open (the summary
/// read), then for
/// `seeks` seconds drawn at random (seeded) the time to hand out every
/// message of [t, t + 1 s) — what replay's seek does before drawing.
#include <cstdint>
#include <filesystem>

#include "haptel/mcap/records.hpp"

namespace haptel::bench {

struct SyntheticSession {
  uint64_t messages = 0;
  uint64_t file_bytes = 0;
  double write_s = 0;  // wall time to write it
};

SyntheticSession WriteSyntheticSession(const std::filesystem::path& path, double duration_s,
                                       mcap::Compression compression = mcap::Compression::kZstd);

struct SeekFigures {
  double open_ms = 0;
  double seek_p50_ms = 0, seek_p95_ms = 0, seek_max_ms = 0;
  uint64_t messages_per_second = 0;  // handed out per seek (the mean)
  double duration_s = 0;             // of the file read
  uint64_t file_bytes = 0;
  size_t chunks = 0;
};

/// Opens `path` and reads one second at `seeks` random seconds of it.
SeekFigures MeasureSeek(const std::filesystem::path& path, int seeks = 100, uint32_t seed = 1);

}  // namespace haptel::bench
