#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/video/synthetic_camera.hpp"

using haptel::video::JpegDecoder;
using haptel::video::JpegEncoder;

namespace {

/// A frame from the grand-prix start, as the vehicle node would send it.
cv::Mat RenderedFrame() {
  static const haptel::Track track(haptel::LoadTrack("config/tracks/grand-prix.yaml"));
  const haptel::video::SyntheticCamera camera(track, haptel::CameraConfig{});
  const haptel::Vec2 start = track.StartPosition();
  cv::Mat image;
  camera.Render({start.x(), start.y(), track.StartHeading()}, image);
  return image;
}

std::vector<uint8_t> Encoded(const cv::Mat& image, int quality) {
  JpegEncoder encoder(quality);
  std::vector<uint8_t> bytes;
  REQUIRE(encoder.Encode(image, bytes));
  return bytes;
}

}  // namespace

TEST_CASE("jpeg encoder accepts quality 1..100 only") {
  CHECK_THROWS_AS(JpegEncoder(0), std::invalid_argument);
  CHECK_THROWS_AS(JpegEncoder(101), std::invalid_argument);
  CHECK_THROWS_AS(JpegEncoder(-5), std::invalid_argument);
  CHECK(JpegEncoder(1).quality() == 1);
  CHECK(JpegEncoder(100).quality() == 100);
}

TEST_CASE("jpeg round trip keeps the size and nearly the pixels") {
  const cv::Mat frame = RenderedFrame();
  const std::vector<uint8_t> bytes = Encoded(frame, 80);
  REQUIRE(bytes.size() > 4);
  CHECK(bytes[0] == 0xFF);
  CHECK(bytes[1] == 0xD8);
  // Compressed well below the raw frame.
  CHECK(bytes.size() < frame.total() * frame.elemSize() / 4);

  JpegDecoder decoder;
  cv::Mat decoded;
  REQUIRE(decoder.Decode(bytes.data(), bytes.size(), decoded));
  CHECK(decoded.size() == frame.size());
  CHECK(decoded.type() == CV_8UC3);
  const double mean_abs_error = cv::norm(frame, decoded, cv::NORM_L1) / (frame.total() * 3.0);
  INFO("mean absolute error " << mean_abs_error);
  CHECK(mean_abs_error < 8.0);
  CHECK(decoder.failures() == 0);
}

TEST_CASE("jpeg: higher quality costs more bytes and loses less") {
  const cv::Mat frame = RenderedFrame();
  const std::vector<uint8_t> low = Encoded(frame, 30);
  const std::vector<uint8_t> high = Encoded(frame, 95);
  CHECK(high.size() > low.size());

  JpegDecoder decoder;
  cv::Mat low_image, high_image;
  REQUIRE(decoder.Decode(low.data(), low.size(), low_image));
  REQUIRE(decoder.Decode(high.data(), high.size(), high_image));
  CHECK(cv::norm(frame, high_image, cv::NORM_L1) < cv::norm(frame, low_image, cv::NORM_L1));
}

TEST_CASE("jpeg encoder replaces the output and reports what it cannot encode") {
  const cv::Mat frame = RenderedFrame();
  JpegEncoder encoder(80);
  std::vector<uint8_t> out(100000, 0x55);
  REQUIRE(encoder.Encode(frame, out));
  REQUIRE(out.size() > 4);
  CHECK(out[0] == 0xFF);
  CHECK(out[1] == 0xD8);
  CHECK(out[out.size() - 2] == 0xFF);
  CHECK(out.back() == 0xD9);
  // The same frame again gives the same bytes, not appended ones.
  const std::vector<uint8_t> first = out;
  REQUIRE(encoder.Encode(frame, out));
  CHECK(out == first);

  CHECK_FALSE(encoder.Encode(cv::Mat(), out));
  CHECK(out.empty());
  CHECK_FALSE(encoder.Encode(cv::Mat(8, 8, CV_64FC(7), cv::Scalar::all(0)), out));
  CHECK(out.empty());
}

TEST_CASE("jpeg decoder rejects empty, garbage and truncated data") {
  const cv::Mat frame = RenderedFrame();
  const std::vector<uint8_t> good = Encoded(frame, 80);
  JpegDecoder decoder;
  cv::Mat image(24, 32, CV_8UC3, cv::Scalar(1, 2, 3));
  const cv::Mat before = image.clone();
  const uchar* data = image.data;
  const auto unchanged = [&] {
    return image.data == data && image.size() == before.size() &&
           cv::norm(image, before, cv::NORM_INF) == 0;
  };

  SECTION("empty") {
    CHECK_FALSE(decoder.Decode(nullptr, 0, image));
    CHECK_FALSE(decoder.Decode(good.data(), 0, image));
    CHECK(decoder.failures() == 2);
    CHECK(unchanged());
  }

  SECTION("random garbage") {
    std::mt19937 rng(7);
    std::vector<uint8_t> garbage(5000);
    for (auto& b : garbage) b = static_cast<uint8_t>(rng());
    CHECK_FALSE(decoder.Decode(garbage.data(), garbage.size(), image));
    // Garbage between a JPEG's start and end markers.
    garbage[0] = 0xFF;
    garbage[1] = 0xD8;
    garbage[garbage.size() - 2] = 0xFF;
    garbage[garbage.size() - 1] = 0xD9;
    CHECK_FALSE(decoder.Decode(garbage.data(), garbage.size(), image));
    CHECK(decoder.failures() == 2);
    CHECK(unchanged());
  }

  SECTION("a JPEG with its headers wiped") {
    std::vector<uint8_t> broken = good;
    std::fill(broken.begin() + 2, broken.begin() + 400, 0x00);
    CHECK_FALSE(decoder.Decode(broken.data(), broken.size(), image));
    CHECK(decoder.failures() == 1);
    CHECK(unchanged());
  }

  SECTION("truncated") {
    for (size_t keep : {size_t{2}, size_t{100}, good.size() / 2, good.size() - 1}) {
      CHECK_FALSE(decoder.Decode(good.data(), keep, image));
    }
    CHECK(decoder.failures() == 4);
    CHECK(unchanged());
  }

  SECTION("failures do not stop later frames from decoding") {
    CHECK_FALSE(decoder.Decode(good.data(), good.size() / 2, image));
    CHECK(decoder.Decode(good.data(), good.size(), image));
    CHECK(image.size() == frame.size());
    CHECK(decoder.failures() == 1);
  }
}

TEST_CASE("jpeg decoder accepts zero padding after the end marker") {
  // V4L2 MJPEG buffers often carry some.
  std::vector<uint8_t> padded = Encoded(RenderedFrame(), 80);
  padded.resize(padded.size() + 16, 0x00);
  JpegDecoder decoder;
  cv::Mat image;
  CHECK(decoder.Decode(padded.data(), padded.size(), image));
  const haptel::CameraConfig camera;
  CHECK(image.size() == cv::Size(camera.width, camera.height));
  CHECK(decoder.failures() == 0);
}

TEST_CASE("jpeg's ladder follows the link: quality, then resolution, then frame rate, and back up") {
  const cv::Mat frame = RenderedFrame();
  JpegEncoder encoder(80, 30.0);
  std::vector<uint8_t> bytes;
  // Sends the next `n` grabbed frames as the camera streamer does; returns
  // the bitrate they took (kbit/s at 30 grabs a second).
  const auto send = [&](int n) {
    size_t total = 0;
    for (int i = 0; i < n; ++i) {
      if (encoder.SkipFrame()) continue;
      REQUIRE(encoder.Encode(frame, bytes));
      total += bytes.size();
    }
    return static_cast<double>(total) * 8.0 * 30.0 / n / 1000.0;
  };
  const double full_kbps = send(30);
  INFO("quality 80, full size: " << full_kbps << " kbit/s");
  CHECK(encoder.quality() == 80);  // not following anything yet: untouched
  REQUIRE(full_kbps > 1000.0);

  // A link a fifth of that: quality first, all the way down.
  encoder.FollowBitrate(full_kbps / 5);
  send(30);
  CHECK(encoder.quality() < 80);
  // Much less: past quality, to half resolution, then to skipped frames.
  encoder.FollowBitrate(full_kbps / 40);
  const double low_kbps = send(150);
  CHECK(encoder.quality() == JpegEncoder::kMinQuality);
  CHECK(encoder.scale() == 0.5);
  CHECK(encoder.skip() >= 1);
  std::vector<uint8_t> small;
  REQUIRE(encoder.Encode(frame, small));
  cv::Mat decoded;
  REQUIRE(JpegDecoder().Decode(small.data(), small.size(), decoded));
  CHECK(decoded.cols == frame.cols / 2);
  INFO("after the ladder: " << low_kbps << " kbit/s for a target of " << full_kbps / 40);
  CHECK(low_kbps < full_kbps / 4);
  // The link clears: back to the top, a rung at a time.
  encoder.FollowBitrate(100000.0);
  send(300);
  CHECK(encoder.skip() == 0);
  CHECK(encoder.scale() == 1.0);
  CHECK(encoder.quality() == 80);  // never above the file's quality
}
