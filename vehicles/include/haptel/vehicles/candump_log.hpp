#pragma once
/// @file Bus traffic in can-utils' `candump -L` format, one frame per line:
/// `(1700000000.123456) can0 02D#0000C03F00000000` (ids of 3 hex digits,
/// 8 for extended and error frames, which carry their flag bits as candump
/// prints them). Read back by python-can's `can.LogReader` and `log2asc`,
/// and by ReadCandumpLog for replaying a run into the decoder.
#include <linux/can.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace haptel::vehicles {

/// "02D#0000C03F00000000"
std::string FormatCandumpFrame(const can_frame& frame);
/// A line's frame part ("02D#00FF"), or false (malformed).
bool ParseCandumpFrame(const std::string& text, can_frame& frame);

struct LoggedFrame {
  double t_s = 0.0;  ///< the line's time stamp
  std::string interface;
  can_frame frame{};
};

/// Every well-formed line of a candump -L log; `malformed` counts the others.
std::vector<LoggedFrame> ReadCandumpLog(const std::filesystem::path& file, size_t* malformed = nullptr);

/// Appends frames to a candump -L file (buffered; flushed on destruction and
/// every `flush_every` frames).
class CandumpWriter {
 public:
  /// Creates the file (and its folder). Throws std::runtime_error naming it.
  CandumpWriter(const std::filesystem::path& file, std::string interface);
  ~CandumpWriter();
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;
  /// One line stamped `wall_ns` (CLOCK_REALTIME).
  void Write(const can_frame& frame, int64_t wall_ns);
  const std::filesystem::path& path() const { return path_; }
  uint64_t lines() const { return lines_; }

 private:
  std::filesystem::path path_;
  std::string interface_;
  std::FILE* file_ = nullptr;
  uint64_t lines_ = 0;
};

}  // namespace haptel::vehicles
