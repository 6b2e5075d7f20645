#include <catch2/catch.hpp>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/testing/lap_frames.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/video/h264_codec.hpp"
#include "haptel/video/image_quality.hpp"

using haptel::CameraCodec;
using haptel::video::DecodeResult;
using haptel::video::EncodedFrameView;
using haptel::video::H264Decoder;
using haptel::video::H264Encoder;

namespace {

/// Two seconds of the synthetic camera driving the grand prix from its start.
const std::vector<cv::Mat>& Frames() {
  static const haptel::Track track(haptel::LoadTrack("config/tracks/grand-prix.yaml"));
  static const std::vector<cv::Mat> frames =
      haptel::testing::LapFrames(track, haptel::CameraConfig{}, 1, 60);
  return frames;
}

struct Sent {
  std::vector<uint8_t> bytes;
  uint64_t seq = 0;
  bool key = false;
};

Sent EncodeNext(H264Encoder& encoder, const cv::Mat& frame, uint64_t seq) {
  Sent s;
  s.seq = seq;
  REQUIRE(encoder.Encode(frame, s.bytes));
  s.key = encoder.last_was_key_frame();
  return s;
}

DecodeResult DecodeSent(H264Decoder& decoder, const Sent& s, cv::Mat& image) {
  return decoder.DecodeFrame(EncodedFrameView{s.bytes.data(), s.bytes.size(), s.seq, s.key}, image);
}

}  // namespace

TEST_CASE("H.264 round trip of the synthetic camera's frames at 1 Mbit/s keeps SSIM above 0.9",
          "[video][h264]") {
  H264Encoder encoder({.width = 640, .height = 480, .rate_hz = 30.0, .bitrate_kbps = 1000});
  H264Decoder decoder;
  cv::Mat image;
  size_t bytes = 0;
  double worst_ssim = 1.0;
  for (size_t i = 0; i < Frames().size(); ++i) {
    const Sent s = EncodeNext(encoder, Frames()[i], i + 1);
    if (i == 0) CHECK(s.key);  // the stream starts with an IDR
    bytes += s.bytes.size();
    REQUIRE(DecodeSent(decoder, s, image) == DecodeResult::kPicture);
    REQUIRE(image.size() == Frames()[i].size());
    REQUIRE(image.type() == CV_8UC3);
    // The first second lets x264's rate control settle.
    if (i >= 30) worst_ssim = std::min(worst_ssim, haptel::video::Ssim(Frames()[i], image));
  }
  CHECK(worst_ssim > 0.9);
  CHECK_FALSE(decoder.awaiting_key_frame());
  // Near the target: 1 Mbit/s is 4.2 kB a frame at 30 fps.
  const double kbps =
      static_cast<double>(bytes) * 8.0 / (static_cast<double>(Frames().size()) / 30.0) / 1000.0;
  CHECK(kbps < 1500.0);
}

TEST_CASE(
    "A frame lost between H.264 encoder and decoder: loss reported, key frame requested, picture "
    "back",
    "[video][h264]") {
  H264Encoder encoder({.width = 640,
                       .height = 480,
                       .rate_hz = 30.0,
                       .bitrate_kbps = 1000,
                       .key_frame_interval_s = 100.0});  // no periodic IDR to rescue it
  H264Decoder decoder;
  cv::Mat image;
  uint64_t seq = 0;
  for (int i = 0; i < 10; ++i)
    REQUIRE(DecodeSent(decoder, EncodeNext(encoder, Frames()[i], ++seq), image) ==
            DecodeResult::kPicture);
  const cv::Mat before = image.clone();

  (void)EncodeNext(encoder, Frames()[10], ++seq);  // lost on the link
  const Sent after_gap = EncodeNext(encoder, Frames()[11], ++seq);
  CHECK_FALSE(after_gap.key);
  CHECK(DecodeSent(decoder, after_gap, image) == DecodeResult::kLost);
  CHECK(decoder.awaiting_key_frame());
  CHECK(cv::norm(image, before, cv::NORM_INF) == 0.0);  // the last picture stays
  // Delta frames are refused until a key frame comes.
  CHECK(DecodeSent(decoder, EncodeNext(encoder, Frames()[12], ++seq), image) ==
        DecodeResult::kAwaitingKeyFrame);

  encoder.RequestKeyFrame();
  const Sent idr = EncodeNext(encoder, Frames()[13], ++seq);
  CHECK(idr.key);
  CHECK(encoder.key_frames() == 2);  // the first frame's and the requested one
  REQUIRE(DecodeSent(decoder, idr, image) == DecodeResult::kPicture);
  CHECK_FALSE(decoder.awaiting_key_frame());
  CHECK(haptel::video::Ssim(Frames()[13], image) > 0.85);
  const Sent next = EncodeNext(encoder, Frames()[14], ++seq);
  CHECK_FALSE(next.key);
  REQUIRE(DecodeSent(decoder, next, image) == DecodeResult::kPicture);
  CHECK(haptel::video::Ssim(Frames()[14], image) > 0.85);
}

TEST_CASE("A corrupt H.264 frame is reported and waits for a key frame", "[video][h264]") {
  H264Encoder encoder({.width = 640,
                       .height = 480,
                       .rate_hz = 30.0,
                       .bitrate_kbps = 1000,
                       .key_frame_interval_s = 100.0});
  H264Decoder decoder;
  cv::Mat image;
  uint64_t seq = 0;
  for (int i = 0; i < 5; ++i)
    REQUIRE(DecodeSent(decoder, EncodeNext(encoder, Frames()[i], ++seq), image) ==
            DecodeResult::kPicture);
  Sent broken = EncodeNext(encoder, Frames()[5], ++seq);
  // A frame cut short and its tail overwritten: what a damaged datagram leaves.
  broken.bytes.resize(broken.bytes.size() / 2);
  for (size_t i = broken.bytes.size() / 2; i < broken.bytes.size(); ++i)
    broken.bytes[i] = static_cast<uint8_t>(i * 37);
  CHECK(DecodeSent(decoder, broken, image) == DecodeResult::kCorrupt);
  CHECK(decoder.awaiting_key_frame());
  encoder.RequestKeyFrame();
  const Sent idr = EncodeNext(encoder, Frames()[6], ++seq);
  REQUIRE(idr.key);
  CHECK(DecodeSent(decoder, idr, image) == DecodeResult::kPicture);
}

TEST_CASE("H.264's target bitrate follows SetTargetBitrate", "[video][h264]") {
  H264Encoder encoder({.width = 640, .height = 480, .rate_hz = 30.0, .bitrate_kbps = 4000});
  std::vector<uint8_t> out;
  auto bytes_over = [&](size_t first, size_t count) {
    size_t total = 0;
    for (size_t i = first; i < first + count; ++i) {
      REQUIRE(encoder.Encode(Frames()[i], out));
      total += out.size();
    }
    return total;
  };
  (void)bytes_over(0, 10);
  const size_t high = bytes_over(10, 20);
  encoder.SetTargetBitrate(300);
  CHECK(encoder.target_bitrate_kbps() == 300);
  (void)bytes_over(30, 10);
  const size_t low = bytes_over(40, 20);
  CHECK(low * 3 < high);
  CHECK_THROWS_AS(encoder.SetTargetBitrate(0), std::invalid_argument);
}

TEST_CASE("H.264 encoder options are checked", "[video][h264]") {
  CHECK_THROWS_AS(H264Encoder({.width = 641, .height = 480}), std::invalid_argument);
  CHECK_THROWS_AS(H264Encoder({.width = 640, .height = 480, .rate_hz = 0.0}),
                  std::invalid_argument);
  CHECK_THROWS_AS(H264Encoder({.width = 640, .height = 480, .rate_hz = 30.0, .bitrate_kbps = 0}),
                  std::invalid_argument);
}

TEST_CASE("The codec seam makes the camera's codec", "[video][h264]") {
  haptel::CameraConfig camera;
  CHECK(haptel::video::MakeVideoEncoder(camera)->codec() == CameraCodec::kJpeg);
  camera.codec = CameraCodec::kH264;
  CHECK(haptel::video::MakeVideoEncoder(camera)->codec() == CameraCodec::kH264);
  CHECK(haptel::video::MakeVideoDecoder(CameraCodec::kH264)->codec() == CameraCodec::kH264);
  CHECK(haptel::video::MakeVideoDecoder(CameraCodec::kJpeg)->codec() == CameraCodec::kJpeg);
}

TEST_CASE("JPEG's quality can be changed between frames", "[video]") {
  haptel::video::JpegEncoder encoder(90);
  std::vector<uint8_t> high, low;
  REQUIRE(encoder.Encode(Frames()[0], high));
  encoder.SetQuality(20);
  CHECK(encoder.quality() == 20);
  REQUIRE(encoder.Encode(Frames()[0], low));
  CHECK(low.size() < high.size());
  CHECK_THROWS_AS(encoder.SetQuality(0), std::invalid_argument);
}

TEST_CASE("SSIM and PSNR of identical and different pictures", "[video]") {
  const cv::Mat& a = Frames()[0];
  CHECK(haptel::video::Ssim(a, a) == Approx(1.0));
  CHECK(std::isinf(haptel::video::PsnrDb(a, a)));
  cv::Mat noisy = a.clone();
  cv::randn(noisy, cv::Scalar::all(0), cv::Scalar::all(20));
  noisy += a;
  CHECK(haptel::video::Ssim(a, noisy) < 0.9);
  CHECK(haptel::video::PsnrDb(a, noisy) < 40.0);
  CHECK_THROWS_AS(haptel::video::Ssim(a, cv::Mat(10, 10, CV_8UC3)), std::invalid_argument);
}
