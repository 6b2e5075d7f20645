// Camera sources: the synthetic camera, a video file and a V4L2 device behind
// one interface. The file cases play a short clip written here with
// cv::VideoWriter (MJPG in AVI): 12 frames, each a solid colour of its own.
#include <sys/stat.h>

#include <array>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/camera_source.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::CameraConfig;
using haptel::CameraSourceKind;
using haptel::ConfigError;
using haptel::video::CameraSource;
using haptel::video::CaptureCamera;
using haptel::video::GrabMonitor;
using haptel::video::MakeCameraSource;

namespace {

constexpr int kFrames = 12;
const cv::Size kClipSize(160, 120);
const std::string kConfigFile = "config/vehicles/test.yaml";  // named in the errors

/// Frame i's colour (BGR): blue steps by 20 a frame, so any two differ by
/// more than JPEG changes a flat colour.
cv::Vec3b ClipColour(int i) {
  return {static_cast<uint8_t>(10 + 20 * i), static_cast<uint8_t>(230 - 15 * i),
          static_cast<uint8_t>((60 + 97 * i) % 256)};
}

int Distance(const cv::Vec3b& a, const cv::Vec3b& b) {
  return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]);
}

/// Which clip frame `image` shows, by its mean colour; -1 if none is close.
int FrameIndex(const cv::Mat& image) {
  const cv::Scalar m = cv::mean(image);
  const cv::Vec3b mean(cv::saturate_cast<uint8_t>(m[0]), cv::saturate_cast<uint8_t>(m[1]),
                       cv::saturate_cast<uint8_t>(m[2]));
  int best = -1;
  int best_distance = 30;  // a flat colour through MJPG stays within a few units
  for (int i = 0; i < kFrames; ++i) {
    const int d = Distance(mean, ClipColour(i));
    if (d < best_distance) {
      best = i;
      best_distance = d;
    }
  }
  return best;
}

/// The 12-frame clip, written once per test process.
const fs::path& Clip() {
  static const fs::path file = [] {
    const fs::path f = haptel::test::ScratchDir("test_camera_source") / "clip.avi";
    cv::VideoWriter writer(f.string(), cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0,
                           kClipSize);
    REQUIRE(writer.isOpened());
    for (int i = 0; i < kFrames; ++i) {
      const cv::Vec3b c = ClipColour(i);
      writer.write(cv::Mat(kClipSize, CV_8UC3, cv::Scalar(c[0], c[1], c[2])));
    }
    writer.release();
    REQUIRE(fs::file_size(f) > 0);
    return f;
  }();
  return file;
}

CameraConfig FileCamera(const fs::path& file, bool loop, cv::Size size = kClipSize) {
  CameraConfig c;
  c.source = CameraSourceKind::kFile;
  c.file = file;
  c.loop = loop;
  c.width = size.width;
  c.height = size.height;
  return c;
}

template <typename F>
std::string ConfigErrorOf(F&& f) {
  return haptel::test::WhatOf<ConfigError>(std::forward<F>(f));
}

}  // namespace

TEST_CASE("file source: frames come back in order, and the first follows the last") {
  const auto source = MakeCameraSource(FileCamera(Clip(), true), nullptr, kConfigFile);
  CHECK_FALSE(source->RendersAtGrab());
  CHECK_THAT(source->Describe(), Contains(Clip().string()));
  cv::Mat image;
  cv::Mat first;
  for (int k = 0; k < 2 * kFrames + 1; ++k) {
    INFO("grab " << k + 1);
    REQUIRE(source->Grab({}, image));
    CHECK(image.size() == kClipSize);
    CHECK(image.type() == CV_8UC3);
    CHECK(FrameIndex(image) == k % kFrames);
    if (k == 0) first = image.clone();
    if (k == kFrames)
      CHECK(cv::norm(image, first, cv::NORM_INF) == 0);  // frame 13 is frame 1 again
  }
  CHECK_FALSE(source->Ended());
  CHECK(dynamic_cast<CaptureCamera&>(*source).loops() == 2);
}

TEST_CASE("file source: a clip of another size is resized to the configured size") {
  SECTION("smaller") {
    const auto source = MakeCameraSource(FileCamera(Clip(), true, {64, 48}), nullptr, kConfigFile);
    CHECK(dynamic_cast<CaptureCamera&>(*source).native_size() == kClipSize);
    cv::Mat image;
    REQUIRE(source->Grab({}, image));
    CHECK(image.size() == cv::Size(64, 48));
    CHECK(FrameIndex(image) == 0);
  }
  SECTION("larger, and another aspect") {
    const auto source =
        MakeCameraSource(FileCamera(Clip(), true, {640, 360}), nullptr, kConfigFile);
    cv::Mat image(10, 10, CV_8UC1);  // a wrong buffer is replaced
    REQUIRE(source->Grab({}, image));
    CHECK(image.size() == cv::Size(640, 360));
    CHECK(image.type() == CV_8UC3);
    REQUIRE(source->Grab({}, image));
    CHECK(FrameIndex(image) == 1);
  }
}

TEST_CASE("file source with loop: false ends after the last frame") {
  const auto source = MakeCameraSource(FileCamera(Clip(), false), nullptr, kConfigFile);
  cv::Mat image;
  for (int k = 0; k < kFrames; ++k) {
    INFO("grab " << k + 1);
    REQUIRE(source->Grab({}, image));
    CHECK(FrameIndex(image) == k);
    CHECK_FALSE(source->Ended());
  }
  const cv::Mat last = image.clone();
  CHECK_FALSE(source->Grab({}, image));
  CHECK(source->Ended());
  CHECK(cv::norm(image, last, cv::NORM_INF) == 0);  // left as it was
  CHECK_FALSE(source->Grab({}, image));
  CHECK(source->Ended());
}

TEST_CASE(
    "file source: a file that cannot be played is a ConfigError naming the key and the path") {
  const fs::path dir = haptel::test::ScratchDir("test_camera_source_bad");
  SECTION("missing") {
    const fs::path missing = dir / "no-such-clip.avi";
    const std::string msg =
        ConfigErrorOf([&] { MakeCameraSource(FileCamera(missing, true), nullptr, kConfigFile); });
    CHECK_THAT(msg, Contains(kConfigFile));
    CHECK_THAT(msg, Contains("'camera.file'"));
    CHECK_THAT(msg, Contains(missing.string()));
    CHECK_THAT(msg, Contains("no such file"));
  }
  SECTION("a folder") {
    const std::string msg =
        ConfigErrorOf([&] { MakeCameraSource(FileCamera(dir, true), nullptr, kConfigFile); });
    CHECK_THAT(msg, Contains("'camera.file'"));
    CHECK_THAT(msg, Contains("not a file"));
  }
  SECTION("not a video") {
    const fs::path text = dir / "notes.avi";
    std::ofstream(text) << "this is not a video\n";
    const std::string msg =
        ConfigErrorOf([&] { MakeCameraSource(FileCamera(text, true), nullptr, kConfigFile); });
    CHECK_THAT(msg, Contains("'camera.file'"));
    CHECK_THAT(msg, Contains(text.string()));
  }
}

TEST_CASE(
    "device source: a device that is not there is a ConfigError naming the key and the device") {
  struct stat st {};
  if (::stat("/dev/video9", &st) == 0) {
    WARN("/dev/video9 exists on this machine: skipped");
    return;
  }
  CameraConfig c;
  c.source = CameraSourceKind::kDevice;
  for (const std::string device : {"/dev/video9", "9"}) {
    INFO("device: " << device);
    c.device = device;
    const std::string msg = ConfigErrorOf([&] { MakeCameraSource(c, nullptr, kConfigFile); });
    CHECK_THAT(msg, Contains(kConfigFile));
    CHECK_THAT(msg, Contains("'camera.device'"));
    CHECK_THAT(msg, Contains("cannot open /dev/video9"));
    CHECK_THAT(msg, Contains("no such device"));
  }
  SECTION("a file that is not a device") {
    c.device = Clip().string();
    const std::string msg = ConfigErrorOf([&] { MakeCameraSource(c, nullptr, kConfigFile); });
    CHECK_THAT(msg, Contains("not a device"));
  }
}

TEST_CASE("synthetic source renders the track from the pose it is given") {
  const haptel::Track track(haptel::LoadTrack("config/tracks/grand-prix.yaml"));
  CameraConfig c;
  c.width = 96;
  c.height = 72;
  const auto source = MakeCameraSource(c, &track, kConfigFile);
  CHECK(source->RendersAtGrab());
  CHECK(source->Describe() == "synthetic");
  cv::Mat a, b;
  REQUIRE(source->Grab({0.0, 0.0, 0.0}, a));
  REQUIRE(source->Grab({1.0, 0.0, 0.5}, b));
  CHECK(a.size() == cv::Size(96, 72));
  CHECK(cv::norm(a, b, cv::NORM_L1) > 0);
  CHECK_FALSE(source->Ended());

  CHECK_THROWS_AS(MakeCameraSource(c, nullptr, kConfigFile), std::invalid_argument);
}

TEST_CASE("grab monitor: a stall is reported once, counted every time") {
  constexpr int64_t kMs = 1'000'000;
  GrabMonitor monitor(3, 1.0);
  using Event = GrabMonitor::Event;
  int64_t t = 0;
  const auto grab = [&](bool ok) {
    t += 33 * kMs;
    return monitor.OnGrab(ok, t);
  };
  CHECK(grab(true) == Event::kNone);
  // Failing, but not yet for a second: no stall.
  for (int i = 0; i < 31; ++i) CHECK(grab(false) == Event::kNone);  // 0.99 s
  CHECK_FALSE(monitor.stalled());
  CHECK(grab(false) == Event::kStalled);  // 32 grabs, 1.023 s after the first failure
  CHECK(monitor.stalled());
  for (int i = 0; i < 50; ++i) CHECK(grab(false) == Event::kNone);  // once
  CHECK(monitor.stalls() == 1);
  CHECK(monitor.failures() == 82);

  CHECK(grab(true) == Event::kNone);  // frames again
  CHECK_FALSE(monitor.stalled());
  CHECK(monitor.failures_in_a_row() == 0);

  // A short hiccup is counted as failures, not as a stall.
  CHECK(grab(false) == Event::kNone);
  CHECK(grab(true) == Event::kNone);
  CHECK(monitor.stalls() == 1);
  CHECK(monitor.failures() == 83);

  // A second stall is counted but not reported again.
  for (int i = 0; i < 40; ++i) CHECK(grab(false) == Event::kNone);
  CHECK(monitor.stalled());
  CHECK(monitor.stalls() == 2);

  SECTION("slow failures (a device read that times out) need the minimum count too") {
    GrabMonitor slow(3, 1.0);
    CHECK(slow.OnGrab(false, 0) == Event::kNone);
    CHECK(slow.OnGrab(false, 1100 * kMs) == Event::kNone);  // 2 failures, 1.1 s
    CHECK(slow.OnGrab(false, 2200 * kMs) == Event::kStalled);
  }
}

TEST_CASE("capture camera: refuses a config CameraConfig::ValidateOrThrow refuses") {
  CameraConfig c = FileCamera(Clip(), true);
  c.width = 8;
  CHECK_THAT(
      haptel::test::WhatOf<haptel::ConfigFieldError>([&] { CaptureCamera camera(c, kConfigFile); }),
      Contains("width: expected a whole number in [16, 4096]"));
  c = CameraConfig{};
  c.source = CameraSourceKind::kDevice;  // and no device
  CHECK_THAT(
      haptel::test::WhatOf<haptel::ConfigFieldError>([&] { CaptureCamera camera(c, kConfigFile); }),
      Contains("device: expected a V4L2 device path"));
}
