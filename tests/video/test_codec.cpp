#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/video/rate_estimator.hpp"
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

/// `count` frames along the grand-prix lap, as the robot's camera sees it
/// driving the centre line (the ladder's bytes vary with what is in view).
std::vector<cv::Mat> LapFrames(int count) {
  static const haptel::Track track(haptel::LoadTrack("config/tracks/grand-prix.yaml"));
  const haptel::video::SyntheticCamera camera(track, haptel::CameraConfig{});
  std::vector<cv::Mat> frames(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double s = track.length() * i / count;
    const haptel::Vec2 p = track.PointAt(s);
    const haptel::Vec2 t = track.TangentAt(s);
    camera.Render({p.x(), p.y(), std::atan2(t.y(), t.x())}, frames[static_cast<size_t>(i)]);
  }
  return frames;
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

TEST_CASE(
    "jpeg's ladder follows the link: quality, then resolution, then frame rate, and back up") {
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
  CHECK(encoder.frame_share() < 1.0);
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
  CHECK(encoder.frame_share() == 1.0);
  CHECK(encoder.scale() == 1.0);
  CHECK(encoder.quality() == 80);  // never above the file's quality
}

TEST_CASE(
    "jpeg's ladder: each rung's bitrate is below the one above, by at most kMaxRungRatio, on real "
    "frames") {
  // A rung more than about 1.4 times the one below cannot be climbed back
  // to: the operator's estimate grows to at most 1.5 times what arrives.
  const std::vector<cv::Mat> frames = LapFrames(8);
  for (const int top : {100, 80, 95, 60, 20}) {
    JpegEncoder encoder(top, 30.0);
    const auto& ladder = encoder.ladder();
    REQUIRE(ladder.size() >= 10);
    CHECK(ladder.front().quality == top);
    CHECK(ladder.front().scale == 1.0);
    CHECK(ladder.front().frame_share == 1.0);
    std::vector<double> kbps;
    std::vector<uint8_t> bytes;
    for (size_t r = 0; r < ladder.size(); ++r) {
      encoder.SetRung(r);
      size_t total = 0;
      for (const cv::Mat& frame : frames) {
        REQUIRE(encoder.Encode(frame, bytes));
        total += bytes.size();
      }
      kbps.push_back(static_cast<double>(total) / frames.size() * 8.0 * 30.0 *
                     ladder[r].frame_share / 1000.0);
    }
    for (size_t r = 1; r < ladder.size(); ++r) {
      INFO("top quality " << top << ", rung " << r << " (quality " << ladder[r].quality
                          << ", scale " << ladder[r].scale << ", frames " << ladder[r].frame_share
                          << "): " << kbps[r] << " kbit/s, the rung above " << kbps[r - 1]
                          << " (guessed ratio "
                          << ladder[r - 1].relative_kbps / ladder[r].relative_kbps << ")");
      CHECK(kbps[r] < kbps[r - 1]);
      CHECK(kbps[r - 1] / kbps[r] <= JpegEncoder::kMaxRungRatio);
      // The first guess is near the measured ratio (the ladder learns the rest).
      CHECK(std::abs(ladder[r - 1].relative_kbps / ladder[r].relative_kbps -
                     kbps[r - 1] / kbps[r]) < 0.15);
    }
    // The bottom: the lowest quality, half size, a quarter of the frames.
    CHECK(ladder.back().quality == std::min(top, JpegEncoder::kMinQuality));
    CHECK(ladder.back().scale == 0.5);
    CHECK(ladder.back().frame_share == 0.25);
  }
}

TEST_CASE("jpeg's ladder climbs back after a cut of the link, through the operator's estimate") {
  // A closed loop on a simulated link: the encoder's frames go through a
  // drop-tail queue of 100 ms at the link's rate, their arrivals feed the
  // operator's RateEstimator, whose target (10 a second) the encoder
  // follows. The link carries 1 Mbit/s, then 0.3, then 1 again. Decided
  // before measuring: back within 70 % of the bitrate before the cut.
  const std::vector<cv::Mat> frames = LapFrames(30);
  JpegEncoder encoder(80, 30.0);
  haptel::video::RateEstimator estimator;
  encoder.FollowBitrate(estimator.target_kbps());
  struct InFlight {
    uint64_t seq;
    double capture_s, arrival_s;
    size_t bytes;
  };
  std::deque<InFlight> in_flight;
  struct Sent {
    double t_s;
    size_t bytes;
  };
  std::vector<Sent> sent;  // what went into the link, when
  double link_free_s = 0.0;
  uint64_t seq = 0;
  std::vector<uint8_t> bytes;
  const auto capacity_kbps = [](double t_s) {
    return t_s < 20.0 ? 1000.0 : t_s < 35.0 ? 300.0 : 1000.0;
  };
  for (int tick = 0; tick < 30 * 75; ++tick) {
    const double now = tick / 30.0;
    while (!in_flight.empty() && in_flight.front().arrival_s <= now) {
      const InFlight f = in_flight.front();
      in_flight.pop_front();
      estimator.OnFrame(f.seq, f.capture_s, f.arrival_s, f.bytes);
    }
    estimator.OnSilence(now);
    if (estimator.FeedbackDue(now)) encoder.FollowBitrate(estimator.target_kbps());
    if (encoder.SkipFrame()) continue;
    REQUIRE(encoder.Encode(frames[static_cast<size_t>(tick) % frames.size()], bytes));
    ++seq;
    // The link's queue: a frame that would wait longer than 100 ms is dropped.
    const double start = std::max(now, link_free_s);
    if (start - now > 0.1) continue;
    link_free_s = start + static_cast<double>(bytes.size()) * 8.0 / (capacity_kbps(now) * 1000.0);
    in_flight.push_back({seq, now, link_free_s + 0.01, bytes.size()});
    sent.push_back({now, bytes.size()});
  }
  const auto kbps_between = [&](double from_s, double to_s) {
    size_t total = 0;
    for (const Sent& s : sent) {
      if (s.t_s >= from_s && s.t_s < to_s) total += s.bytes;
    }
    return static_cast<double>(total) * 8.0 / (to_s - from_s) / 1000.0;
  };
  const double before_cut = kbps_between(15.0, 20.0);
  const double during_cut = kbps_between(30.0, 35.0);
  const double after = kbps_between(70.0, 75.0);
  INFO("before the cut " << before_cut << " kbit/s, during " << during_cut << ", 35 s after "
                         << after << "; the estimate at the end " << estimator.target_kbps()
                         << " kbit/s");
  CHECK(before_cut > 500.0);  // the link is used before the cut
  CHECK(during_cut < 330.0);  // the ladder went down to fit
  CHECK(after >= 0.7 * before_cut);
}

TEST_CASE(
    "a camera's JPEG: its size read from the frame header without decoding, baseline and "
    "progressive") {
  const cv::Mat frame = RenderedFrame();
  int width = 0;
  int height = 0;
  const std::vector<uint8_t> baseline = Encoded(frame, 80);
  REQUIRE(haptel::video::JpegFrameSize(baseline.data(), baseline.size(), width, height));
  CHECK(width == 640);
  CHECK(height == 480);
  cv::Mat small;
  cv::resize(frame, small, cv::Size(320, 240));
  std::vector<uint8_t> progressive;
  REQUIRE(cv::imencode(".jpg", small, progressive, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  REQUIRE(haptel::video::JpegFrameSize(progressive.data(), progressive.size(), width, height));
  CHECK(width == 320);
  CHECK(height == 240);
  // Not a JPEG, or cut before its frame header: no size.
  const std::vector<uint8_t> garbage{0x89, 'P', 'N', 'G', 0, 0, 0, 0};
  CHECK_FALSE(haptel::video::JpegFrameSize(garbage.data(), garbage.size(), width, height));
  CHECK_FALSE(haptel::video::JpegFrameSize(baseline.data(), 20, width, height));
  CHECK_FALSE(haptel::video::JpegFrameSize(nullptr, 0, width, height));
}

TEST_CASE(
    "a camera's JPEG passes through undecoded only at the configured size, as JPEG, within the "
    "asked bitrate") {
  const std::vector<uint8_t> jpeg = Encoded(RenderedFrame(), 80);  // 640x480
  haptel::CameraConfig camera;                                     // 640x480 JPEG at 30 Hz
  const double kbps = static_cast<double>(jpeg.size()) * 8.0 * camera.rate_hz / 1000.0;
  INFO(jpeg.size() << " bytes a frame: " << kbps << " kbit/s at 30 Hz");
  // No bitrate asked for yet, or one it fits: as it is.
  CHECK(haptel::video::JpegPassesThrough(jpeg.data(), jpeg.size(), camera, 0));
  CHECK(haptel::video::JpegPassesThrough(jpeg.data(), jpeg.size(), camera,
                                         static_cast<uint32_t>(kbps) + 1));
  // Over the bitrate the link carries: encoded again (down the ladder).
  CHECK_FALSE(haptel::video::JpegPassesThrough(jpeg.data(), jpeg.size(), camera,
                                               static_cast<uint32_t>(kbps * 0.8)));
  // Another size than the vehicle file's, or a vehicle that sends H.264: encoded again.
  haptel::CameraConfig smaller = camera;
  smaller.width = 320;
  smaller.height = 240;
  CHECK_FALSE(haptel::video::JpegPassesThrough(jpeg.data(), jpeg.size(), smaller, 0));
  haptel::CameraConfig h264 = camera;
  h264.codec = haptel::CameraCodec::kH264;
  CHECK_FALSE(haptel::video::JpegPassesThrough(jpeg.data(), jpeg.size(), h264, 0));
  // Decoded when it cannot pass: at the configured size.
  cv::Mat scratch;
  cv::Mat picture;
  REQUIRE(haptel::video::DecodeCameraJpeg(jpeg, smaller, scratch, picture));
  CHECK(picture.cols == 320);
  CHECK(picture.rows == 240);
  CHECK_FALSE(haptel::video::DecodeCameraJpeg(std::vector<uint8_t>(jpeg.begin(), jpeg.begin() + 10),
                                              smaller, scratch, picture));
  CHECK(picture.cols == 320);  // left as it was
}
