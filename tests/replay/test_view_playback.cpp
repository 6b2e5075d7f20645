// haptel replay's view: a session file's view frames and video drawn again.
// The replay clock as the keys steer it; an MP4 rendered from a file whose
// frames match the frames the renderer draws from the same models and
// pictures (SSIM computed by video::Ssim on frames FFmpeg decodes through
// OpenCV's videoio); a file cut mid-chunk, as a killed recording leaves it,
// read to its last whole chunk.
#include <fastdds/rtps/common/SerializedPayload.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "haptel/mcap/reader.hpp"
#include "haptel/mcap/writer.hpp"
#include "haptel/record/session_channels.hpp"
#include "haptel/replay/view_playback.hpp"
#include "haptel/session/foxglovePubSubTypes.h"
#include "haptel/video/h264_codec.hpp"
#include "haptel/video/image_quality.hpp"
#include "haptel/view/canvas.hpp"
#include "haptel/view/view_record.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

constexpr uint64_t kT0 = 1'800'000'000'000'000'000;  // CLOCK_REALTIME ns
constexpr double kFps = 10.0;
constexpr int kFrames = 24;
constexpr int kWidth = 320;
constexpr int kHeight = 180;

/// The camera's picture k: a gradient with a bar that moves.
cv::Mat Picture(int k) {
  cv::Mat bgr(120, 160, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x)
      bgr.at<cv::Vec3b>(y, x) = {static_cast<uint8_t>(x), static_cast<uint8_t>(y * 2), 90};
  cv::rectangle(bgr, cv::Rect(10 + 5 * k, 30, 20, 60), cv::Scalar(240, 240, 240), cv::FILLED);
  return bgr;
}

/// Frame k's model as the live view drew it: a hand that moves, the overlay.
view::ViewFrame Frame(int k, int64_t capture_ns) {
  view::ViewFrame f;
  view::Shape palm;
  palm.kind = view::ShapeKind::kBox;
  palm.position = {0.1 + 0.01 * k, 0.05, 0.0};
  palm.size = {0.04, 0.05, 0.01};
  palm.color = {0.93f, 0.76f, 0.64f, 1.0f};
  f.model.shapes.push_back(palm);
  std::snprintf(f.model.overlay.interface_name, sizeof f.model.overlay.interface_name, "gesture");
  f.model.overlay.t_s = k / kFps;
  f.model.overlay.gates_total = 5;
  f.model.overlay.gates_passed = k / 10;
  f.view_t_s = k / kFps;
  f.copies = k == 5 ? 2 : 1;  // one slow frame, recorded twice live
  f.video_capture_wall_ns = capture_ns;
  return f;
}

std::vector<uint8_t> CompressedVideo(const std::vector<uint8_t>& h264, int64_t capture_ns) {
  foxglove::CompressedVideo m;
  m.timestamp().sec(static_cast<uint32_t>(capture_ns / 1'000'000'000));
  m.timestamp().nsec(static_cast<uint32_t>(capture_ns % 1'000'000'000));
  m.frame_id("camera");
  m.data(h264);
  m.format("h264");
  foxglove::CompressedVideoPubSubType type;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.getSerializedSizeProvider(&m)());
  REQUIRE(type.serialize(&m, &payload));
  return {payload.data, payload.data + payload.length};
}

/// A session file as a run with a view writes it: the set-up, then each
/// frame's picture (received) and view frame (drawn a little later); a
/// chunk flushed halfway, where `flushed_size` says the file ended then.
void WriteSession(const std::filesystem::path& file, uintmax_t* flushed_size = nullptr) {
  mcap::Writer writer(file, {});
  const uint16_t view_schema =
      writer.AddSchema(view::kViewFrameSchemaName, "omgidl", view::kViewRecordIdl);
  const uint16_t setup_schema =
      writer.AddSchema(view::kViewSetupSchemaName, "omgidl", view::kViewRecordIdl);
  const uint16_t video_schema =
      writer.AddSchema(std::string(record::session::kCompressedVideoSchema), "omgidl",
                       std::string(record::session::FoxgloveIdl()));
  const uint16_t setup_channel = writer.AddChannel(setup_schema, view::kViewSetupTopic, "cdr");
  const uint16_t view_channel = writer.AddChannel(view_schema, view::kViewFrameTopic, "cdr");
  const uint16_t video_channel =
      writer.AddChannel(video_schema, record::session::VideoTopic("robot"), "cdr");
  view::ViewSetup setup;
  setup.width = kWidth;
  setup.height = kHeight;
  setup.record_fps = kFps;
  std::vector<uint8_t> bytes;
  view::EncodeViewSetup(setup, bytes);
  writer.Write(setup_channel, 0, kT0, kT0, bytes.data(), bytes.size());
  video::H264Encoder::Options o;
  o.width = 160;
  o.height = 120;
  o.rate_hz = kFps;
  video::H264Encoder encoder(o);
  std::vector<uint8_t> h264;
  for (int k = 0; k < kFrames; ++k) {
    const uint64_t t = kT0 + static_cast<uint64_t>(k * 1e9 / kFps);
    const auto capture = static_cast<int64_t>(t - 20'000'000);
    REQUIRE(encoder.Encode(Picture(k), h264));
    const std::vector<uint8_t> video = CompressedVideo(h264, capture);
    writer.Write(video_channel, static_cast<uint32_t>(k + 1), t + 1'000'000,
                 static_cast<uint64_t>(capture), video.data(), video.size());
    view::EncodeViewFrame(Frame(k, capture), bytes);
    writer.Write(view_channel, static_cast<uint32_t>(k), t + 5'000'000, t + 5'000'000, bytes.data(),
                 bytes.size());
    if (k == kFrames / 2) {
      writer.Flush();
      if (flushed_size != nullptr) *flushed_size = std::filesystem::file_size(file);
    }
  }
  writer.Close();
}

/// What the renderer draws for frame k with its picture: the live frame.
std::vector<cv::Mat> DrawnLive() {
  view::ViewOptions options;
  options.mode = view::ViewMode::kOffscreen;
  options.width = kWidth;
  options.height = kHeight;
  view::Canvas canvas(options);
  video::H264Encoder::Options o;
  o.width = 160;
  o.height = 120;
  o.rate_hz = kFps;
  video::H264Encoder encoder(o);
  video::H264Decoder decoder;
  std::vector<uint8_t> h264;
  std::vector<cv::Mat> frames;
  for (int k = 0; k < kFrames; ++k) {
    REQUIRE(encoder.Encode(Picture(k), h264));
    cv::Mat picture;
    video::EncodedFrameView e{h264.data(), h264.size(), static_cast<uint64_t>(k + 1), k == 0};
    REQUIRE(decoder.DecodeFrame(e, picture) == video::DecodeResult::kPicture);
    view::ViewFrame f = Frame(k, 1);
    f.model.video.image = std::make_shared<const cv::Mat>(picture);
    f.model.video.id = static_cast<uint64_t>(k + 1);
    canvas.renderer().Draw(f.model, f.view_t_s);
    cv::Mat bgr;
    canvas.renderer().ReadPixels(bgr);
    for (int c = 0; c < f.copies; ++c) frames.push_back(bgr.clone());
  }
  return frames;
}

}  // namespace

TEST_CASE(
    "the replay clock plays at its speed, pauses, steps a frame and seeks within the record") {
  const uint64_t start = 1'000'000'000'000;
  const uint64_t end = start + 60'000'000'000;  // a minute
  replay::ReplayClock clock(start, end, 2.0, 0.1);
  CHECK(clock.Now(0) == start);
  CHECK(clock.Now(1'000'000'000) == start + 2'000'000'000);  // twice as fast
  clock.TogglePause(1'000'000'000);
  CHECK(clock.paused());
  CHECK(clock.Now(5'000'000'000) == start + 2'000'000'000);  // held
  clock.Step(1, 5'000'000'000);
  CHECK(clock.Now(9'000'000'000) == start + 2'100'000'000);
  clock.Step(-3, 9'000'000'000);
  CHECK(clock.Now(9'000'000'000) == start + 1'800'000'000);
  clock.Seek(-5.0, 9'000'000'000);  // not before the start
  CHECK(clock.Now(9'000'000'000) == start);
  clock.TogglePause(10'000'000'000);
  CHECK_FALSE(clock.paused());
  clock.Seek(70.0, 10'000'000'000);  // not past the end
  CHECK(clock.Now(10'000'000'000) == end);
  CHECK(clock.ended(10'000'000'000));
  clock.Home(11'000'000'000);
  CHECK(clock.Now(12'000'000'000) == start + 2'000'000'000);
}

TEST_CASE("a replayed MP4 holds the frames the live view drew, each as often as it recorded it") {
  const std::filesystem::path dir = test::ScratchDir("replay_mp4");
  const std::filesystem::path file = dir / "session.mcap";
  WriteSession(file);
  const mcap::Reader reader = mcap::Reader::Open(file);
  replay::ViewPlayback playback(reader);
  CHECK(playback.has_view());
  CHECK(playback.setup().width == kWidth);
  const replay::ReplayReport report = replay::RenderReplayMp4(playback, 0.0, dir / "replay.mp4");
  CHECK(report.frames == kFrames);
  CHECK(report.mp4_frames == kFrames + 1);
  CHECK(report.pictures == kFrames);
  CHECK(report.pictures_missing == 0);

  const std::vector<cv::Mat> live = DrawnLive();
  cv::VideoCapture mp4((dir / "replay.mp4").string(), cv::CAP_FFMPEG);
  REQUIRE(mp4.isOpened());
  cv::Mat frame;
  size_t n = 0;
  double worst = 1.0;
  while (mp4.read(frame)) {
    REQUIRE(n < live.size());
    worst = std::min(worst, video::Ssim(live[n], frame));
    ++n;
  }
  CHECK(n == live.size());
  INFO("worst SSIM " << worst);
  CHECK(worst >= 0.95);
}

TEST_CASE("a session file cut mid-chunk, as a killed recording leaves it, replays to its cut") {
  const std::filesystem::path dir = test::ScratchDir("replay_cut");
  const std::filesystem::path file = dir / "killed.mcap";
  uintmax_t flushed = 0;
  WriteSession(file, &flushed);
  // Killed while it wrote the chunk after the flush: no summary, no footer,
  // a torn chunk at the end.
  REQUIRE(std::filesystem::file_size(file) > flushed + 100);
  std::filesystem::resize_file(file, flushed + 100);
  const mcap::Reader reader = mcap::Reader::Open(file);
  CHECK(reader.recovered());
  replay::ViewPlayback playback(reader);
  const replay::ReplayReport report = replay::ReadReplay(playback, 0.0);
  CHECK(report.frames == kFrames / 2 + 1);  // every frame flushed, none after
  CHECK(report.pictures == report.frames);
  CHECK(report.pictures_missing == 0);
  CHECK(report.pictures_undecoded == 0);
}

TEST_CASE(
    "a seek plays from the sought frame with its own picture, decoded from the key frame "
    "before it") {
  const std::filesystem::path dir = test::ScratchDir("replay_seek");
  const std::filesystem::path file = dir / "session.mcap";
  WriteSession(file);
  const mcap::Reader reader = mcap::Reader::Open(file);
  replay::ViewPlayback playback(reader);
  // Frame 15 of 24 (10 fps; a key frame every second, at 0, 10 and 20).
  const uint64_t from = kT0 + static_cast<uint64_t>(15 * 1e9 / kFps);
  std::vector<int64_t> shown;
  playback.Play(from, playback.end_ns() + 1, [&](const view::ViewFrame& f, uint64_t) {
    shown.push_back(f.video_capture_wall_ns);
    CHECK(f.model.video.image != nullptr);
  });
  CHECK(shown.size() == kFrames - 15);
  CHECK(playback.pictures_missing() == 0);
  CHECK(playback.pictures_undecoded() == 0);
  // Read on from where it ended: nothing more; back to the start: all of it.
  size_t more = 0;
  playback.Play(playback.end_ns() + 1, playback.end_ns() + 2,
                [&](const view::ViewFrame&, uint64_t) { ++more; });
  CHECK(more == 0);
  playback.Play(playback.start_ns(), from, [&](const view::ViewFrame&, uint64_t) { ++more; });
  CHECK(more == 15);
  CHECK(playback.pictures_missing() == 0);
}
