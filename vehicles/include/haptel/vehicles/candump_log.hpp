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

/// How a bus log fares, as the CAN robot reports it on its own topic
/// (haptel/<vehicle>/can_log: CanLogReport, can_robot.hpp).
struct CanLogStatus {
  std::string path;          ///< on the vehicle's host; "": no log kept
  uint64_t frames = 0;       ///< frames certainly in the file (its last flush)
  uint64_t frames_lost = 0;  ///< frames not in it because a write failed
  std::string error;         ///< why the log ended; "" while it is whole

  bool operator==(const CanLogStatus&) const = default;
};

struct LoggedFrame {
  double t_s = 0.0;  ///< the line's time stamp
  std::string interface;
  can_frame frame{};
};

/// Every well-formed line of a candump -L log; `malformed` counts the others.
std::vector<LoggedFrame> ReadCandumpLog(const std::filesystem::path& file,
                                        size_t* malformed = nullptr);

/// Appends frames to a candump -L file: buffered, and flushed every
/// kFlushEvery frames, at least every kFlushPeriod_ns of the frames' stamps,
/// and at Close(), each flush checked.
///
/// A write that fails (a full disk: ENOSPC; a file size limit: EFBIG; EIO)
/// ends the log: the file is closed, the failure kept in error() and said
/// once on stderr, and every frame from then on — with those still in the
/// buffer — is counted as lost instead of written. It never throws then:
/// the vehicle goes on driving, and its state reports the log's end.
class CandumpWriter {
 public:
  static constexpr uint64_t kFlushEvery = 256;
  static constexpr int64_t kFlushPeriod_ns = 500'000'000;

  /// Creates the file (and its folder). Throws std::runtime_error naming it.
  CandumpWriter(const std::filesystem::path& file, std::string interface);
  /// Close()s.
  ~CandumpWriter();
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;
  /// One line stamped `wall_ns` (CLOCK_REALTIME).
  void Write(const can_frame& frame, int64_t wall_ns);
  /// Flushes and closes the file; false if that or an earlier write failed.
  bool Close();
  const std::filesystem::path& path() const { return path_; }
  /// Frames handed to Write.
  uint64_t lines() const { return lines_; }
  /// Frames known to be in the file: those of the last flush that succeeded.
  uint64_t frames_written() const { return flushed_; }
  /// Frames that are not (certainly) in the file because a write failed.
  uint64_t frames_lost() const { return error_.empty() ? 0 : lines_ - flushed_; }
  /// "" while the log is whole; else "cannot write FILE: <the OS's reason>
  /// (after N frames)", N being frames_written().
  const std::string& error() const { return error_; }

 private:
  void Flush();
  void Fail(int errno_value);

  std::filesystem::path path_;
  std::string interface_;
  std::FILE* file_ = nullptr;
  uint64_t lines_ = 0;
  uint64_t flushed_ = 0;
  int64_t flushed_wall_ns_ = 0;
  std::string error_;
};

}  // namespace haptel::vehicles
