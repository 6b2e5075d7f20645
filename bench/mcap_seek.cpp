#include "mcap_seek.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "haptel/mcap/reader.hpp"
#include "haptel/mcap/writer.hpp"

namespace haptel::bench {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

SyntheticSession WriteSyntheticSession(const std::filesystem::path& path, double duration_s,
                                       mcap::Compression compression) {
  const auto start = Clock::now();
  mcap::WriterOptions options;
  options.profile = "haptel";
  options.compression = compression;
  mcap::Writer writer(path, options);
  const uint16_t raw = writer.AddSchema("bench::Bytes", "jsonschema", "{}");
  const uint16_t haptic = writer.AddChannel(raw, "/haptic", "application/octet-stream");
  const uint16_t command = writer.AddChannel(raw, "/command", "application/octet-stream");
  const uint16_t state = writer.AddChannel(raw, "/state", "application/octet-stream");
  const uint16_t video = writer.AddChannel(raw, "/video", "application/octet-stream");
  std::mt19937 rng(3);
  std::vector<double> servo(25);  // 200 bytes
  std::vector<uint8_t> frame(8192);
  const std::vector<uint8_t> small(96, 7);
  SyntheticSession result;
  const auto ticks = static_cast<uint64_t>(duration_s * 1000.0);
  uint32_t sequence[4] = {};
  for (uint64_t tick = 0; tick < ticks; ++tick) {
    const uint64_t t_ns = tick * 1'000'000ull;
    const double t = tick * 1e-3;
    for (size_t i = 0; i < servo.size(); ++i) servo[i] = std::sin(t * (1.0 + 0.1 * i)) * 0.2;
    writer.Write(haptic, sequence[0]++, t_ns, t_ns, servo.data(), servo.size() * sizeof(double));
    if (tick % 20 == 0) {
      writer.Write(command, sequence[1]++, t_ns, t_ns, small.data(), 48);
      writer.Write(state, sequence[2]++, t_ns + 300'000, t_ns + 300'000, small.data(), 96);
      result.messages += 2;
    }
    if (tick * 30 % 1000 < 30) {  // 30 fps
      const size_t size = tick % 1000 < 34 ? 8192 : 1800 + rng() % 500;
      for (size_t i = 0; i < size; i += 4) {
        const uint32_t r = rng();
        std::copy_n(reinterpret_cast<const uint8_t*>(&r), std::min<size_t>(4, size - i),
                    frame.begin() + i);
      }
      writer.Write(video, sequence[3]++, t_ns, t_ns, frame.data(), size);
      ++result.messages;
    }
    ++result.messages;
  }
  writer.Close();
  result.file_bytes = std::filesystem::file_size(path);
  result.write_s = MsSince(start) * 1e-3;
  return result;
}

SeekFigures MeasureSeek(const std::filesystem::path& path, int seeks, uint32_t seed) {
  SeekFigures figures;
  // From the disk, not the page cache the writing left: this file's pages
  // are dropped (they are clean: the writer synced them), no other file's.
  if (const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC); fd >= 0) {
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
    ::close(fd);
  }
  const auto open_start = Clock::now();
  const mcap::Reader reader = mcap::Reader::Open(path);
  figures.open_ms = MsSince(open_start);
  const mcap::Statistics& st = reader.statistics();
  figures.duration_s = (st.message_end_time_ns - st.message_start_time_ns) * 1e-9;
  figures.file_bytes = std::filesystem::file_size(path);
  figures.chunks = reader.summary().chunk_indexes.size();
  std::mt19937 rng(seed);
  std::vector<double> ms;
  uint64_t handed_out = 0;
  const auto whole_seconds = static_cast<uint64_t>(std::max(1.0, std::floor(figures.duration_s)));
  for (int i = 0; i < seeks; ++i) {
    const uint64_t from = st.message_start_time_ns + (rng() % whole_seconds) * 1'000'000'000ull;
    const auto start = Clock::now();
    reader.ForEachMessage(from, from + 1'000'000'000ull, {},
                          [&](const mcap::MessageView&) { ++handed_out; });
    ms.push_back(MsSince(start));
  }
  std::sort(ms.begin(), ms.end());
  if (!ms.empty()) {
    figures.seek_p50_ms = ms[ms.size() / 2];
    figures.seek_p95_ms = ms[std::min(ms.size() - 1, ms.size() * 95 / 100)];
    figures.seek_max_ms = ms.back();
    figures.messages_per_second = handed_out / ms.size();
  }
  return figures;
}

}  // namespace haptel::bench
