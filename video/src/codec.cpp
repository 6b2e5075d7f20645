#include "haptel/video/codec.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <utility>

#include "haptel/video/h264_codec.hpp"

namespace haptel::video {

namespace {

/// A JPEG's bytes at `quality` as a share of its bytes at quality 80, on
/// the synthetic camera's 640x480 frames (measured with the ladder's test;
/// between the points, linear).
double QualityBytes(int quality) {
  static constexpr std::array<std::pair<int, double>, 15> kPoints{{{1, 0.40},
                                                                   {20, 0.558},
                                                                   {30, 0.61},
                                                                   {40, 0.652},
                                                                   {50, 0.691},
                                                                   {60, 0.758},
                                                                   {70, 0.879},
                                                                   {80, 1.00},
                                                                   {85, 1.14},
                                                                   {90, 1.35},
                                                                   {92, 1.46},
                                                                   {94, 1.74},
                                                                   {96, 2.03},
                                                                   {98, 2.52},
                                                                   {100, 3.62}}};
  for (size_t i = 1; i < kPoints.size(); ++i) {
    if (quality <= kPoints[i].first) {
      const auto [q0, b0] = kPoints[i - 1];
      const auto [q1, b1] = kPoints[i];
      return b0 + (b1 - b0) * (quality - q0) / (q1 - q0);
    }
  }
  return kPoints.back().second;
}

/// A JPEG's bytes at `scale` of its width and height, as a share of full
/// size's: less than the area's share (edges and headers stay).
double ScaleBytes(double scale) { return std::pow(scale, 1.6); }

}  // namespace

std::vector<JpegRung> JpegLadder(int top_quality) {
  if (top_quality < 1 || top_quality > 100) {
    throw std::invalid_argument("JpegLadder: quality " + std::to_string(top_quality) +
                                ", expected 1..100");
  }
  // Steps of 1 or 2 near 100, where the bytes grow fastest; of 10 below 80,
  // where they change little (quality 20 is still more than half the bytes
  // of 80 on the synthetic camera: resolution is where the bytes are).
  static constexpr std::array<int, 15> kQualities{100, 99, 98, 96, 94, 92, 90, 85,
                                                  80,  70, 60, 50, 40, 30, 20};
  static constexpr std::array<double, 5> kScales{0.875, 0.75, 0.625, 0.5625, 0.5};
  static constexpr std::array<double, 6> kFrameShares{4.0 / 5, 2.0 / 3, 1.0 / 2,
                                                      2.0 / 5, 1.0 / 3, 1.0 / 4};
  const double top_bytes = QualityBytes(top_quality);
  std::vector<JpegRung> ladder;
  const auto add = [&](int quality, double scale, double share) {
    ladder.push_back(
        {quality, scale, share, QualityBytes(quality) / top_bytes * ScaleBytes(scale) * share});
  };
  add(top_quality, 1.0, 1.0);
  for (const int q : kQualities) {
    if (q < top_quality && q >= JpegEncoder::kMinQuality) add(q, 1.0, 1.0);
  }
  const int bottom_quality = ladder.back().quality;
  for (const double scale : kScales) add(bottom_quality, scale, 1.0);
  for (const double share : kFrameShares) add(bottom_quality, kScales.back(), share);
  return ladder;
}

JpegEncoder::JpegEncoder(int quality, double frame_rate_hz)
    : quality_(quality), frame_rate_hz_(frame_rate_hz > 0 ? frame_rate_hz : 30.0) {
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("JpegEncoder: quality " + std::to_string(quality) +
                                ", expected 1..100");
  }
  params_ = {cv::IMWRITE_JPEG_QUALITY, quality_};
  ladder_ = JpegLadder(quality);
  measured_kbps_.assign(ladder_.size(), 0.0);
}

void JpegEncoder::SetQuality(int quality) {
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("JpegEncoder: quality " + std::to_string(quality) +
                                ", expected 1..100");
  }
  quality_ = quality;
  params_[1] = quality;
}

void JpegEncoder::SetRung(size_t rung) {
  if (rung >= ladder_.size()) {
    throw std::out_of_range("JpegEncoder::SetRung: rung " + std::to_string(rung) + " of " +
                            std::to_string(ladder_.size()));
  }
  if (frames_at_rung_ > 0) measured_kbps_[rung_] = rung_kbps_;
  rung_ = rung;
  SetQuality(ladder_[rung].quality);
  frames_at_rung_ = 0;
  // The first frame grabbed at a rung is sent; the share counts from it.
  frame_credit_ = 1.0 - ladder_[rung].frame_share;
}

bool JpegEncoder::SkipFrame() {
  const double share = ladder_[rung_].frame_share;
  if (share >= 1.0) return false;
  // Sends `share` of the frames, spread evenly (2/3: two of every three).
  frame_credit_ += share;
  if (frame_credit_ >= 1.0 - 1e-9) {
    frame_credit_ -= 1.0;
    return false;
  }
  return true;
}

bool JpegEncoder::Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) {
  out.clear();  // keeps capacity; imencode resizes it
  if (bgr.empty()) return false;
  try {
    const cv::Mat* source = &bgr;
    const double scale = ladder_[rung_].scale;
    if (scale < 1.0) {
      // Whole pixels, even (chroma subsampling works on 2x2 blocks).
      const int width = std::max(2, static_cast<int>(std::lround(bgr.cols * scale / 2)) * 2);
      const int height = std::max(2, static_cast<int>(std::lround(bgr.rows * scale / 2)) * 2);
      cv::resize(bgr, scaled_, cv::Size(width, height), 0, 0, cv::INTER_AREA);
      source = &scaled_;
    }
    if (!cv::imencode(".jpg", *source, out, params_)) {
      out.clear();
      return false;
    }
  } catch (const cv::Exception&) {  // unsupported depth or channel count
    out.clear();
    return false;
  }
  Climb(out.size());
  return true;
}

double JpegEncoder::Predicted(size_t to) const {
  // Rung by rung from here: each step by the ratio last measured between
  // the two rungs when both were, else by the ladder's guess.
  double kbps = rung_kbps_;
  const auto ratio = [&](size_t upper, size_t lower) {
    if (measured_kbps_[upper] > 0 && measured_kbps_[lower] > 0) {
      return measured_kbps_[upper] / measured_kbps_[lower];
    }
    return ladder_[upper].relative_kbps / ladder_[lower].relative_kbps;
  };
  for (size_t r = rung_; r > to; --r) kbps *= ratio(r - 1, r);
  for (size_t r = rung_; r < to; ++r) kbps /= ratio(r, r + 1);
  return kbps;
}

void JpegEncoder::Climb(size_t bytes) {
  if (target_kbps_ <= 0.0) return;
  // The rung's bitrate, smoothed over its frames.
  const double kbps =
      static_cast<double>(bytes) * 8.0 * frame_rate_hz_ * ladder_[rung_].frame_share / 1000.0;
  rung_kbps_ = frames_at_rung_ == 0 ? kbps : 0.7 * rung_kbps_ + 0.3 * kbps;
  if (++frames_at_rung_ < kFramesPerRung) return;
  measured_kbps_[rung_] = rung_kbps_;
  if (rung_kbps_ > kDownMargin * target_kbps_) {
    // Down: to the highest rung predicted to fit, so a deep cut is not
    // followed a rung per kFramesPerRung frames.
    size_t next = rung_ + 1;
    while (next + 1 < ladder_.size() && Predicted(next) > target_kbps_) ++next;
    if (next < ladder_.size()) SetRung(next);
    return;
  }
  // Up, a rung at a time, when the rung above is predicted to fit.
  if (rung_ > 0 && Predicted(rung_ - 1) <= kUpMargin * target_kbps_) SetRung(rung_ - 1);
}

namespace {

/// Cheap framing check before handing bytes to libjpeg: a JPEG starts with the
/// SOI marker and ends with EOI, possibly followed by zero padding (V4L2 MJPEG
/// buffers often carry some). libjpeg itself only *warns* about a stream cut
/// short in the scan data and returns a partly grey image, so without this a
/// truncated frame would count as decoded.
bool LooksLikeCompleteJpeg(const uint8_t* data, size_t size) {
  if (size < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
  size_t end = size;
  while (end > 2 && data[end - 1] == 0x00) --end;
  return end >= 4 && data[end - 2] == 0xFF && data[end - 1] == 0xD9;
}

}  // namespace

bool JpegDecoder::Decode(const uint8_t* data, size_t size, cv::Mat& image) {
  if (data == nullptr || size > static_cast<size_t>(std::numeric_limits<int>::max()) ||
      !LooksLikeCompleteJpeg(data, size)) {
    ++failures_;
    return false;
  }
  // Wraps the caller's bytes without copying; imdecode only reads them.
  const cv::Mat raw(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
  cv::Mat decoded;
  try {
    // Decodes into a fresh Mat (not into `image`): OpenCV releases its output
    // on failure, and `image` must stay untouched then.
    decoded = cv::imdecode(raw, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    decoded.release();
  }
  if (decoded.empty()) {
    ++failures_;
    return false;
  }
  image = decoded;
  return true;
}

DecodeResult JpegDecoder::DecodeFrame(const EncodedFrameView& frame, cv::Mat& image) {
  return Decode(frame.data, frame.size, image) ? DecodeResult::kPicture : DecodeResult::kCorrupt;
}

bool JpegFrameSize(const uint8_t* data, size_t size, int& width, int& height) {
  if (data == nullptr || size < 4 || data[0] != 0xFF || data[1] != 0xD8) return false;
  size_t at = 2;
  while (at + 4 <= size) {
    if (data[at] != 0xFF) return false;
    const uint8_t marker = data[at + 1];
    if (marker == 0xFF) {  // fill byte before a marker
      ++at;
      continue;
    }
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {  // no length
      at += 2;
      continue;
    }
    if (marker == 0xD9 || marker == 0xDA)
      return false;  // end, or scan data before any frame header
    const size_t length = (static_cast<size_t>(data[at + 2]) << 8) | data[at + 3];
    if (length < 2 || at + 2 + length > size) return false;
    // SOF0..SOF15 but DHT (C4), JPG (C8) and DAC (CC): precision, height, width.
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      if (length < 7) return false;
      height = (data[at + 5] << 8) | data[at + 6];
      width = (data[at + 7] << 8) | data[at + 8];
      return width > 0 && height > 0;
    }
    at += 2 + length;
  }
  return false;
}

bool PngFrameSize(const uint8_t* data, size_t size, int& width, int& height) {
  static constexpr uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  // Signature, then the IHDR chunk: length 13, "IHDR", width, height (big-endian).
  if (data == nullptr || size < 24 || std::memcmp(data, kSignature, 8) != 0 ||
      std::memcmp(data + 12, "IHDR", 4) != 0) {
    return false;
  }
  const auto be32 = [&](size_t at) {
    return (uint32_t{data[at]} << 24) | (uint32_t{data[at + 1]} << 16) |
           (uint32_t{data[at + 2]} << 8) | data[at + 3];
  };
  const uint32_t w = be32(16);
  const uint32_t h = be32(20);
  // PNG allows up to 2^31 - 1 each way.
  if (be32(8) != 13 || w == 0 || h == 0 || w > 0x7FFFFFFFu || h > 0x7FFFFFFFu) return false;
  width = static_cast<int>(w);
  height = static_cast<int>(h);
  return true;
}

bool JpegPassesThrough(const uint8_t* data, size_t size, const CameraConfig& camera,
                       uint32_t target_kbps) {
  if (camera.codec != CameraCodec::kJpeg) return false;
  int width = 0;
  int height = 0;
  if (!JpegFrameSize(data, size, width, height) || width != camera.width || height != camera.height)
    return false;
  if (target_kbps == 0) return true;
  const double kbps = static_cast<double>(size) * 8.0 * camera.rate_hz / 1000.0;
  return kbps <= target_kbps;
}

bool DecodeCameraJpeg(const std::vector<uint8_t>& jpeg, const CameraConfig& camera,
                      cv::Mat& scratch, cv::Mat& bgr_out) {
  if (jpeg.empty()) return false;
  const cv::Mat bytes(1, static_cast<int>(jpeg.size()), CV_8UC1, const_cast<uint8_t*>(jpeg.data()));
  scratch = cv::imdecode(bytes, cv::IMREAD_COLOR);
  if (scratch.empty()) return false;
  const cv::Size size(camera.width, camera.height);
  if (scratch.size() == size) {
    scratch.copyTo(bgr_out);
  } else {
    cv::resize(scratch, bgr_out, size, 0, 0, cv::INTER_AREA);
  }
  return true;
}

std::unique_ptr<VideoEncoder> MakeVideoEncoder(const CameraConfig& camera) {
  switch (camera.codec) {
    case CameraCodec::kJpeg:
      return std::make_unique<JpegEncoder>(camera.jpeg_quality, camera.rate_hz);
    case CameraCodec::kH264:
      return std::make_unique<H264Encoder>(
          H264Encoder::Options{.width = camera.width,
                               .height = camera.height,
                               .rate_hz = camera.rate_hz,
                               .bitrate_kbps = camera.bitrate_kbps});
  }
  throw std::invalid_argument("MakeVideoEncoder: unknown codec");
}

std::unique_ptr<VideoDecoder> MakeVideoDecoder(CameraCodec codec) {
  switch (codec) {
    case CameraCodec::kJpeg:
      return std::make_unique<JpegDecoder>();
    case CameraCodec::kH264:
      return std::make_unique<H264Decoder>();
  }
  throw std::invalid_argument("MakeVideoDecoder: unknown codec");
}

}  // namespace haptel::video
