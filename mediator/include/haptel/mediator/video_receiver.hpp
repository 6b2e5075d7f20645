#pragma once
/// @file Receives the vehicle's video frames and decodes them off the DDS thread.
///
/// The DDS callback only swaps the bytes into a slot (latest frame wins); a
/// decoder thread turns them into the screen image and measures latency from
/// the capture stamp (CLOCK_REALTIME of the vehicle's host: meaningful when
/// both run on one host or on hosts whose clocks are synchronised).
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "haptel/core/histogram.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/video/codec.hpp"

namespace haptel::mediator {

struct VideoStats {
  uint64_t frames = 0;          ///< frames received and (when decoding) decoded
  uint64_t dropped = 0;         ///< replaced in the slot before the decoder got to them
  uint64_t decode_failures = 0; ///< corrupt frames, counted and dropped
  double fps = 0.0;
  double latency_ms_p50 = 0.0;  ///< capture -> decoded
  double latency_ms_p99 = 0.0;
};

/// The latest decoded image, shared (never copied) with whoever shows it.
struct LatestFrame {
  std::shared_ptr<const cv::Mat> image;  ///< BGR; null before the first frame
  uint64_t id = 0;                       ///< grows with each decoded frame
  int64_t capture_wall_ns = 0;           ///< the vehicle's capture stamp
};

class VideoReceiver {
 public:
  /// Subscribes to `topic` on `participant`. With `decode` false frames are
  /// only counted (no screen to show them on).
  VideoReceiver(link::Participant& participant, const std::string& topic, bool decode);
  ~VideoReceiver();

  VideoStats Stats() const;
  /// Copy of the latest decoded image (empty before the first).
  cv::Mat Screen() const;
  /// The latest decoded image without copying it: a short lock, any thread.
  LatestFrame Latest() const;
  /// The latest good frame as it came (JPEG), copied; empty before the
  /// first. Any thread, now and then (a console's thumbnail), decoding or not.
  std::vector<uint8_t> LatestPicture() const;

 private:
  void OnFrame(const msg::VideoFrame& frame);
  void DecodeLoop();

  bool decode_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<uint8_t> pending_;
  int64_t pending_capture_ns_ = 0;
  bool has_pending_ = false;
  bool stop_ = false;
  LatestFrame latest_;
  std::vector<uint8_t> last_bytes_;  ///< the latest good frame's bytes
  video::JpegDecoder decoder_;
  Histogram latency_{100.0, 5000};  // µs bins up to 500 ms
  uint64_t frames_ = 0;
  uint64_t dropped_ = 0;
  uint64_t decode_failures_ = 0;
  int64_t first_frame_ns_ = 0;
  int64_t last_frame_ns_ = 0;
  std::thread decoder_thread_;
  std::unique_ptr<link::VideoReader> reader_;  // last: destroyed first
};

}  // namespace haptel::mediator
