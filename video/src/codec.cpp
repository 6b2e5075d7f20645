#include "haptel/video/codec.hpp"

#include <limits>
#include <stdexcept>
#include <string>

#include "haptel/video/h264_codec.hpp"

#include <opencv2/imgcodecs.hpp>

namespace haptel::video {

JpegEncoder::JpegEncoder(int quality) : quality_(quality) {
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

bool JpegEncoder::Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) {
  out.clear();  // keeps capacity; imencode resizes it
  if (bgr.empty()) return false;
  try {
    if (!cv::imencode(".jpg", bgr, out, params_)) {
      out.clear();
      return false;
    }
  } catch (const cv::Exception&) {  // unsupported depth or channel count
    out.clear();
    return false;
  }
  return true;
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

std::unique_ptr<VideoEncoder> MakeVideoEncoder(const CameraConfig& camera) {
  switch (camera.codec) {
    case CameraCodec::kJpeg:
      return std::make_unique<JpegEncoder>(camera.jpeg_quality);
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
