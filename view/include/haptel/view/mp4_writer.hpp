#pragma once
/// @file An H.264 MP4 file written with FFmpeg's own libraries (libavformat,
/// libavcodec with libx264), frame by frame, that says when a write fails.
///
/// Why not cv::VideoWriter: its write() returns void and its FFmpeg backend
/// drops the muxer's error codes, so a full disk went unnoticed — the run
/// said "recorded" and left a file cut at 64 kB with no index. Here every
/// packet's write is checked (libavformat keeps the OS error of the buffered
/// write, e.g. ENOSPC or EFBIG), as are the trailer and the close.
///
/// The file is a fragmented MP4 (an empty `moov` first, then a `moof` +
/// `mdat` fragment per key frame, one a second): a file cut by a full disk
/// or a killed program still plays up to its last whole fragment, where a
/// plain MP4 without its final `moov` plays nothing.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace haptel::view {

class Mp4Writer {
 public:
  /// Opens `file` (created or truncated) for frames of `width`×`height`
  /// pixels (positive, even) at `fps` frames per second. Throws ViewError
  /// naming the file and why it cannot be written.
  Mp4Writer(const std::filesystem::path& file, int width, int height, double fps);
  /// Close()s if that was not done, ignoring the result.
  ~Mp4Writer();
  Mp4Writer(const Mp4Writer&) = delete;
  Mp4Writer& operator=(const Mp4Writer&) = delete;

  /// Encodes one frame: 8-bit BGR (CV_8UC3), width×height. Returns false
  /// once the file has failed: the first failure ends the recording (the
  /// encoder and the file are released; what was written stays) and is
  /// kept in error(); later calls do nothing.
  bool Write(const cv::Mat& bgr);
  /// Flushes the encoder, writes the last fragment and closes the file.
  /// False if this or any earlier write failed. Calling it again returns the
  /// same answer.
  bool Close();

  bool failed() const { return !error_.empty(); }
  /// "" while everything was written; else one line naming the file, the
  /// OS's reason and how many frames it holds, e.g. "cannot write
  /// /data/run.mp4: No space left on device (the recording ended after 312
  /// frames)".
  const std::string& error() const { return error_; }
  /// Frames handed to the encoder before the recording ended.
  uint64_t frames() const { return frames_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  struct Ffmpeg;
  /// Sends `frame` (null: flush) and writes every packet the encoder gives.
  bool Encode(bool flush);
  /// Keeps the first failure and releases everything.
  void Fail(const std::string& what, int av_error);

  std::filesystem::path file_;
  int width_ = 0;
  int height_ = 0;
  std::unique_ptr<Ffmpeg> av_;
  cv::Mat yuv_;
  std::string error_;
  uint64_t frames_ = 0;
  bool closed_ = false;
};

}  // namespace haptel::view
