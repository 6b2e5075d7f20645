// The MP4 writer behind --record: what it writes decodes, and a write that
// fails (a file size limit standing in for a full disk) ends the recording,
// says which file and why, and leaves what was written playable; the View
// carries that failure to its stats and keeps drawing.
#include <catch2/catch.hpp>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "file_size_limit.hpp"
#include "haptel/view/mp4_writer.hpp"
#include "haptel/view/view.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::view;

namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;

/// Frame `i`: noise (so the file grows fast) under a bar that moves.
cv::Mat Frame(int i) {
  cv::Mat bgr(kHeight, kWidth, CV_8UC3);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::rectangle(bgr, cv::Rect((i * 8) % kWidth, 0, 16, kHeight), cv::Scalar(0, 0, 255), cv::FILLED);
  return bgr;
}

int DecodedFrames(const std::filesystem::path& mp4) {
  cv::VideoCapture video(mp4.string(), cv::CAP_FFMPEG);
  if (!video.isOpened()) return -1;
  int frames = 0;
  cv::Mat frame;
  while (video.read(frame)) ++frames;
  return frames;
}

/// Serves a fresh noise picture every frame: the MP4 grows by kilobytes a frame.
class NoiseSource final : public ViewSource {
 public:
  void Fill(ViewModel& model) override {
    auto image = std::make_shared<cv::Mat>(240, 320, CV_8UC3);
    cv::randu(*image, cv::Scalar::all(0), cv::Scalar::all(255));
    model.video.image = image;
    model.video.id = ++calls_;
    model.video.capture_wall_ns = 0;
  }
  uint64_t calls_ = 0;
};

}  // namespace

TEST_CASE("Mp4Writer writes every frame into an H.264 MP4 that decodes at its frame rate") {
  const auto mp4 = test::ScratchDir("mp4-writer") / "whole.mp4";
  {
    Mp4Writer writer(mp4, kWidth, kHeight, 25.0);
    for (int i = 0; i < 40; ++i) REQUIRE(writer.Write(Frame(i)));
    CHECK(writer.Close());
    CHECK(writer.error().empty());
    CHECK(writer.frames() == 40);
  }
  cv::VideoCapture video(mp4.string(), cv::CAP_FFMPEG);
  REQUIRE(video.isOpened());
  CHECK(video.get(cv::CAP_PROP_FRAME_WIDTH) == kWidth);
  CHECK(video.get(cv::CAP_PROP_FRAME_HEIGHT) == kHeight);
  CHECK(video.get(cv::CAP_PROP_FPS) == Approx(25.0));
  CHECK(DecodedFrames(mp4) == 40);
}

TEST_CASE(
    "Mp4Writer: a write that fails ends the recording, names the file and the OS's reason, and "
    "keeps what was written") {
  const auto mp4 = test::ScratchDir("mp4-writer-full") / "cut.mp4";
  constexpr rlim_t kLimit =
      2 * 1024 * 1024;  // bytes: some whole fragments, far less than the frames
  constexpr int kFrames = 600;
  Mp4Writer writer(mp4, kWidth, kHeight, 10.0);
  int accepted = 0;
  bool closed = true;
  {
    test::FileSizeLimit limit(kLimit);
    for (int i = 0; i < kFrames && writer.Write(Frame(i)); ++i) ++accepted;
    closed = writer.Close();
  }
  INFO(writer.error());
  CHECK(accepted < kFrames);
  CHECK_FALSE(closed);
  CHECK(writer.failed());
  CHECK(writer.error().find(mp4.string()) != std::string::npos);
  CHECK(writer.error().find(std::strerror(EFBIG)) != std::string::npos);  // "File too large"
  CHECK(writer.error().find("after " + std::to_string(writer.frames()) + " frames") !=
        std::string::npos);
  // Ended: nothing more is taken, the answer stays.
  const std::string error = writer.error();
  CHECK_FALSE(writer.Write(Frame(0)));
  CHECK_FALSE(writer.Close());
  CHECK(writer.error() == error);
  CHECK(std::filesystem::file_size(mp4) <= kLimit);
  // A fragmented MP4: the whole fragments before the failure still play.
  const int decoded = DecodedFrames(mp4);
  CHECK(decoded >= 10);
  CHECK(decoded <= accepted);
}

TEST_CASE(
    "the View: a recording whose file fails ends, its stats say why, and the view goes on "
    "drawing") {
  const auto mp4 = test::ScratchDir("view-mp4-full") / "view.mp4";
  NoiseSource source;
  ViewOptions options;
  options.mode = ViewMode::kOffscreen;
  options.width = 640;
  options.height = 360;
  options.record = mp4;
  View view(options, source, nullptr);
  {
    test::FileSizeLimit limit(64 * 1024);
    // Bounds the wait; asserts no timing.
    REQUIRE(test::WaitFor([&] { return !view.Stats().record_error.empty(); }, 60.0));
  }
  const uint64_t frames = view.Stats().frames;
  REQUIRE(test::WaitFor([&] { return view.Stats().frames > frames + 5; }, 60.0));
  view.Stop();
  const ViewStats stats = view.Stats();
  CHECK(stats.record_error.find(mp4.string()) != std::string::npos);
  CHECK(stats.record_error.find(std::strerror(EFBIG)) != std::string::npos);
  CHECK(std::filesystem::file_size(mp4) <= 64 * 1024);
}
