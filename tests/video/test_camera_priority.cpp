// The vehicle's camera loop renders and encodes behind the control loop and
// the link's threads: it runs kBackgroundNiceSteps below the node's other
// threads, so that on a busy host a command and its state never wait for a
// frame's encode (issue 24: commands and states come first; the command
// round trip's p99 was 3.8 times raw Fast DDS's). Priorities are asserted,
// never timings.
#include <algorithm>
#include <atomic>
#include <catch2/catch.hpp>
#include <memory>
#include <opencv2/core.hpp>

#include "haptel/core/loop_meter.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/video/camera_streamer.hpp"
#include "test_env.hpp"

using namespace haptel;

namespace {

/// A camera that notes the priority of the thread it is grabbed on.
class PriorityNotingCamera final : public video::CameraSource {
 public:
  bool Grab(const video::CameraPose&, cv::Mat& bgr_out) override {
    nice.store(ThreadNice());
    bgr_out = cv::Mat(48, 64, CV_8UC3, cv::Scalar(40, 80, 120));
    grabs.fetch_add(1);
    return true;
  }
  std::string Describe() const override { return "priority-noting stand-in"; }

  std::atomic<int> nice{-100};
  std::atomic<int> grabs{0};
};

}  // namespace

TEST_CASE(
    "CameraStreamer: frames are grabbed and encoded below the priority of the node's other threads",
    "[video]") {
  LinkConfig link;
  link.domain_id = test::UniqueDomain(71);
  link::Participant participant(link, "test-camera-priority");
  auto camera = std::make_unique<PriorityNotingCamera>();
  PriorityNotingCamera& seen = *camera;
  CameraConfig config;
  config.codec = CameraCodec::kJpeg;
  config.width = 64;
  config.height = 48;
  config.rate_hz = 50.0;
  const int node_nice = ThreadNice();
  video::CameraStreamer streamer(config, std::move(camera), participant, "robot1",
                                 [] { return link::WriterId{}; });
  streamer.Start();
  REQUIRE(test::WaitFor(
      [&] { return seen.grabs.load() >= 2 && streamer.Counters().frames_published >= 1; }, 30.0));
  streamer.Stop();
  CHECK(seen.nice.load() == std::min(19, node_nice + kBackgroundNiceSteps));
  CHECK(ThreadNice() ==
        node_nice);  // the node's own thread (its control loop's creator) keeps its priority
}
