#pragma once
/// @file JPEG encoding and decoding of video frames (OpenCV imgcodecs).
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace haptel::video {

class JpegEncoder {
 public:
  /// @param quality JPEG quality 1..100; throws std::invalid_argument otherwise.
  explicit JpegEncoder(int quality);
  /// Encodes a BGR image into `out` (replacing its contents, reusing capacity).
  /// Returns false (and leaves `out` empty) when OpenCV cannot encode it.
  bool Encode(const cv::Mat& bgr, std::vector<uint8_t>& out);
  int quality() const { return quality_; }

 private:
  int quality_;
  std::vector<int> params_;
};

class JpegDecoder {
 public:
  /// Decodes JPEG bytes into `image` (BGR). Returns false for empty or corrupt
  /// data, counting it in failures(); `image` is then left unchanged.
  bool Decode(const uint8_t* data, size_t size, cv::Mat& image);
  uint64_t failures() const { return failures_; }

 private:
  uint64_t failures_ = 0;
};

}  // namespace haptel::video
