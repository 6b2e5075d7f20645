#include "haptel/video/codec.hpp"

#include <limits>
#include <stdexcept>
#include <string>

#include "haptel/video/h264_codec.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace haptel::video {

JpegEncoder::JpegEncoder(int quality, double frame_rate_hz)
    : quality_(quality), top_quality_(quality), frame_rate_hz_(frame_rate_hz > 0 ? frame_rate_hz : 30.0) {
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("JpegEncoder: quality " + std::to_string(quality) +
                                ", expected 1..100");
  }
  params_ = {cv::IMWRITE_JPEG_QUALITY, quality_};
}

void JpegEncoder::SetQuality(int quality) {
  if (quality < 1 || quality > 100) {
    throw std::invalid_argument("JpegEncoder: quality " + std::to_string(quality) + ", expected 1..100");
  }
  quality_ = quality;
  params_[1] = quality;
}

bool JpegEncoder::SkipFrame() {
  if (skip_ == 0) return false;
  // Keep one frame, skip the next skip_.
  const bool skip = skip_count_ % (skip_ + 1) != 0;
  ++skip_count_;
  return skip;
}

bool JpegEncoder::Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) {
  out.clear();  // keeps capacity; imencode resizes it
  if (bgr.empty()) return false;
  try {
    const cv::Mat* source = &bgr;
    if (scale_ < 1.0) {
      cv::resize(bgr, scaled_, cv::Size(), scale_, scale_, cv::INTER_AREA);
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

void JpegEncoder::Climb(size_t bytes) {
  if (target_kbps_ <= 0.0) return;
  // The rung's bitrate, smoothed over its frames.
  const double kbps = static_cast<double>(bytes) * 8.0 * frame_rate_hz_ / (skip_ + 1) / 1000.0;
  rung_kbps_ = frames_at_rung_ == 0 ? kbps : 0.7 * rung_kbps_ + 0.3 * kbps;
  if (++frames_at_rung_ < kFramesPerRung) return;
  const auto moved = [&] { frames_at_rung_ = 0; };
  if (rung_kbps_ > 1.05 * target_kbps_) {
    // Down: quality, then resolution, then frame rate.
    if (quality_ > kMinQuality) {
      SetQuality(std::max(kMinQuality, quality_ - 10));
    } else if (scale_ == 1.0) {
      scale_ = 0.5;
    } else if (skip_ < kMaxSkip) {
      ++skip_;
    } else {
      return;  // the bottom rung: nothing more to give
    }
    moved();
    return;
  }
  // Up, a rung at a time, when the rung above is predicted to fit: a frame
  // rate step by its ratio of frames, full resolution at about 3.5 times the
  // bytes of half (the shipped camera's pictures), 10 quality about 1.25.
  double above = 0.0;
  if (skip_ > 0) {
    above = rung_kbps_ * (skip_ + 1) / skip_;
  } else if (scale_ < 1.0) {
    above = rung_kbps_ * 3.5;
  } else if (quality_ < top_quality_) {
    above = rung_kbps_ * 1.25;
  } else {
    return;  // the top rung
  }
  if (above > 0.9 * target_kbps_) return;
  if (skip_ > 0) {
    --skip_;
  } else if (scale_ < 1.0) {
    scale_ = 1.0;
  } else {
    SetQuality(std::min(top_quality_, quality_ + 10));
  }
  moved();
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
    if (marker == 0xD9 || marker == 0xDA) return false;  // end, or scan data before any frame header
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

bool JpegPassesThrough(const uint8_t* data, size_t size, const CameraConfig& camera, uint32_t target_kbps) {
  if (camera.codec != CameraCodec::kJpeg) return false;
  int width = 0;
  int height = 0;
  if (!JpegFrameSize(data, size, width, height) || width != camera.width || height != camera.height) return false;
  if (target_kbps == 0) return true;
  const double kbps = static_cast<double>(size) * 8.0 * camera.rate_hz / 1000.0;
  return kbps <= target_kbps;
}

bool DecodeCameraJpeg(const std::vector<uint8_t>& jpeg, const CameraConfig& camera, cv::Mat& scratch,
                      cv::Mat& bgr_out) {
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
      return std::make_unique<H264Encoder>(H264Encoder::Options{.width = camera.width,
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
