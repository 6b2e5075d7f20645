// The link's rate estimate over a real DDS link (issue 40): it measures the
// network's queue, not the CPU of the hosts at either end. A receiver whose
// cores are busy (spinning threads, its decoder decoding) and whose sender
// hands frames to the link later and later after their capture (a loaded
// host's encoder) sees no cut on a link without a queue; a link that queues
// (the fault transport's rate stage) is still cut. And a vehicle shown only
// as a fleet's tile is asked for a preview, and gives the full picture back
// when it is driven again.
#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <memory>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/testing/lap_frames.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/camera_streamer.hpp"
#include "haptel/video/h264_codec.hpp"
#include "haptel/video/video_receiver.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

/// Threads that spin on every core (two per core) until destroyed.
class BusyCores {
 public:
  BusyCores() {
    const unsigned n = 2 * std::max(1u, std::thread::hardware_concurrency());
    for (unsigned i = 0; i < n; ++i) {
      threads_.emplace_back([this] {
        volatile uint64_t spins = 0;
        while (!stop_.load(std::memory_order_relaxed)) spins = spins + 1;
      });
    }
  }
  ~BusyCores() {
    stop_ = true;
    for (std::thread& t : threads_) t.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

}  // namespace

TEST_CASE("a busy receiving host on a link with no queue: the rate estimate is never cut",
          "[video]") {
  // Three seconds of the lap, encoded beforehand at 3 Mbit/s (before the
  // link: a matched sender that sends nothing is a silent link): the decoder's work.
  const Track track(LoadTrack("config/tracks/grand-prix.yaml"));
  const std::vector<cv::Mat> lap = testing::LapFrames(track, CameraConfig{}, 1, 30);
  video::H264Encoder encoder({.width = 640, .height = 480, .rate_hz = 30.0, .bitrate_kbps = 3000});
  constexpr int kFrames = 90;
  std::vector<std::vector<uint8_t>> encoded(kFrames);
  std::vector<bool> key(kFrames);
  for (int i = 0; i < kFrames; ++i) {
    REQUIRE(
        encoder.Encode(lap[static_cast<size_t>(i) % lap.size()], encoded[static_cast<size_t>(i)]));
    key[static_cast<size_t>(i)] = encoder.last_was_key_frame();
  }

  LinkConfig config;
  config.domain_id = test::UniqueDomain(69);
  link::Participant vehicle(config, "test-vehicle");
  link::Participant op(config, "test-operator");
  video::VideoReceiver receiver(op, "robot1", /*session=*/7, /*decode=*/true);
  link::VideoWriter writer(vehicle, link::TopicName("robot1", "video"), link::Profile::kVideo);
  REQUIRE(test::WaitFor([&] { return writer.matched() > 0; }, 20.0));

  // Until the receiver hears the writer (a best-effort reader drops what
  // comes before it matched), a key frame now and then.
  uint64_t seq = 0;
  msg::VideoFrame f;
  f.width(640);
  f.height(480);
  f.encoding("h264");
  REQUIRE(test::WaitFor(
      [&] {
        f.seq(++seq);
        f.capture_wall_ns(WallNs());
        f.key_frame(true);
        f.data() = encoded[0];
        writer.Write(f);
        return receiver.Stats().frames > 0;
      },
      20.0));

  const video::VideoStats before = receiver.Stats();
  double least_target_kbps = before.target_kbps;
  {
    const BusyCores busy;
    // At 30 frames a second, each written 4 ms later after its capture
    // than the one before: its capture stamp says the delay grows by 12 %
    // of the time (the old estimator's trend: a cut within a second), the
    // link's stamps that nothing queues.
    const int64_t start = MonotonicNs();
    const int64_t start_wall = WallNs();
    for (int i = 0; i < kFrames; ++i) {
      const int64_t tick = SToNs(i / 30.0);
      SleepUntilNs(start + tick + static_cast<int64_t>(i) * 4'000'000);
      f.seq(++seq);
      f.capture_wall_ns(start_wall + tick);
      f.key_frame(key[static_cast<size_t>(i)]);
      f.data() = encoded[static_cast<size_t>(i)];
      writer.Write(f);
      least_target_kbps = std::min(least_target_kbps, receiver.Stats().target_kbps);
    }
  }
  // Read as the last frame is sent: a sender that stops is a silent link,
  // which the estimate answers by halving (RateEstimator::OnSilence).
  const video::VideoStats after = receiver.Stats();
  INFO("decoded " << after.frames - before.frames << " of " << kFrames << ", lost "
                  << after.frames_lost - before.frames_lost << ", dropped "
                  << after.dropped - before.dropped << ", skipped "
                  << after.frames_skipped - before.frames_skipped << "; least target "
                  << least_target_kbps << " kbit/s, " << after.rate_cuts << " cuts");
  CHECK(after.frames > before.frames);  // the decoder worked on the busy cores
  CHECK(after.rate_cuts == 0);
  CHECK(least_target_kbps >= 20000.0);  // the receiver's start (the most), throughout
}

TEST_CASE("a link that queues (a 1 Mbit/s rate stage, a deep queue): the rate estimate is cut",
          "[video]") {
  LinkConfig vehicle_config;
  vehicle_config.domain_id = test::UniqueDomain(70);
  LinkConfig op_config = vehicle_config;
  op_config.fault.enabled = true;
  op_config.fault.rate_bps = 1e6;
  op_config.fault.queue_s = 3.0;  // deep: the delay grows, nothing is dropped
  link::Participant vehicle(vehicle_config, "test-vehicle");
  link::Participant op(op_config, "test-operator");
  video::VideoReceiver receiver(op, "robot1", /*session=*/7, /*decode=*/false);
  link::VideoWriter writer(vehicle, link::TopicName("robot1", "video"), link::Profile::kVideo);
  REQUIRE(test::WaitFor([&] { return writer.matched() > 0; }, 20.0));
  msg::VideoFrame f;
  f.encoding("jpeg");
  f.key_frame(true);
  f.data() = std::vector<uint8_t>(6000, 0x55);  // 30 a second: 1.44 Mbit/s
  uint64_t seq = 0;
  REQUIRE(test::WaitFor(
      [&] {
        f.seq(++seq);
        f.capture_wall_ns(WallNs());
        writer.Write(f);
        return receiver.Stats().frames > 0;
      },
      20.0));
  const int64_t start = MonotonicNs();
  for (int i = 0; i < 90 && receiver.Stats().rate_cuts == 0; ++i) {
    SleepUntilNs(start + SToNs(i / 30.0));
    f.seq(++seq);
    f.capture_wall_ns(WallNs());
    writer.Write(f);
  }
  // The queue builds 0.44 s of delay a second: cut once the trend shows it.
  CHECK(test::WaitFor([&] { return receiver.Stats().rate_cuts > 0; }, 5.0));
  INFO("target " << receiver.Stats().target_kbps << " kbit/s");
  CHECK(receiver.Stats().target_kbps < 1000.0);
}

TEST_CASE(
    "a vehicle shown only as a tile sends a preview (half the size, at most 10 frames a second); "
    "driven again, the full picture",
    "[video]") {
  const Track track(LoadTrack("config/tracks/test-short.yaml"));
  LinkConfig link;
  link.domain_id = test::UniqueDomain(83);
  CameraConfig camera;
  camera.codec = CameraCodec::kH264;
  link::Participant vehicle(link, "test-vehicle");
  link::Participant op(link, "test-operator");
  video::CameraStreamer streamer(camera, std::make_unique<video::SyntheticSource>(track, camera),
                                 vehicle, "robot1", [] { return link::WriterId{}; });
  video::VideoReceiver receiver(op, "robot1", /*session=*/7, /*decode=*/true);
  streamer.Start();
  const auto width = [&] {
    const video::Frame latest = receiver.Latest();
    return latest.image ? latest.image->cols : 0;
  };
  REQUIRE(test::WaitFor([&] { return width() == camera.width; }, 30.0));

  receiver.ShowAsTile(true);
  CHECK(receiver.Stats().tile);
  REQUIRE(test::WaitFor([&] { return width() == camera.width / 2; }, 10.0));
  CHECK(streamer.Counters().preview);
  // Previews keep coming, no faster than their rate: counted over a second
  // at least, and over however long a loaded machine takes for one (the
  // camera's thread runs niced).
  const uint64_t previews = streamer.Counters().preview_frames;
  const int64_t from = MonotonicNs();
  SleepUntilNs(from + 1'000'000'000);
  CHECK(test::WaitFor([&] { return streamer.Counters().preview_frames > previews; }, 30.0));
  const double elapsed_s = NsToS(MonotonicNs() - from);
  const uint64_t sent = streamer.Counters().preview_frames - previews;
  INFO(sent << " previews in " << elapsed_s << " s");
  CHECK(static_cast<double>(sent) <= elapsed_s * video::CameraStreamer::kPreviewRate_hz + 2.0);

  receiver.ShowAsTile(false);
  CHECK(test::WaitFor([&] { return width() == camera.width; }, 10.0));
  CHECK_FALSE(streamer.Counters().preview);
  CHECK_FALSE(receiver.Latest().stale);
}
