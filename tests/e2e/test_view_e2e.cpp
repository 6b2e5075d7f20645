// End to end with the operator's view: a real X server (Xvfb), the real
// `haptel` window, keys sent to it with xdotool, and the MP4 it records.
#include <catch2/catch.hpp>
#include <signal.h>

#include <cstdlib>
#include <opencv2/videoio.hpp>
#include <regex>

#include "child.hpp"
#include "xserver.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;
using haptel::test::XDoTool;
using haptel::test::XServer;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// The speed in the newest progress line on stderr ("speed 0.12 m/s"), or -1.
double LastSpeed(const std::string& err) {
  static const std::regex speed(R"(speed (-?[0-9.]+) m/s)");
  double last = -1.0;
  for (auto it = std::sregex_iterator(err.begin(), err.end(), speed); it != std::sregex_iterator(); ++it) {
    last = std::stod((*it)[1]);
  }
  return last;
}

}  // namespace

TEST_CASE("a lap in a window under Xvfb, recorded to an MP4 that decodes at 25 frames per second of lap or more") {
  XServer x;
  const auto dir = test::ScratchDir("e2e-view-lap");
  const auto mp4 = dir / "lap.mp4";
  Child run({Bin("haptel"), "run", "--operator", "auto", "--view", "window", "--record", mp4.string(), "--track",
             "config/tracks/test-short.yaml", "--json", "--quiet", "--domain", std::to_string(test::UniqueDomain(31)),
             "--database", (dir / "runs.db").string(), "--vehicle-timeout", "5"});
  const int code = run.Wait(180.0);
  INFO(run.out() << run.err());
  REQUIRE(code == 0);
  const std::string json = run.LastLine();
  for (const char* key : {"view_fps", "view_frame_p99_ms", "video_to_screen_ms_p50", "video_to_screen_ms_p99",
                          "distance_m", "operator", "device", "interface_switches"}) {
    CHECK_FALSE(JsonField(json, key).empty());
  }
  CHECK(std::stod(JsonField(json, "view_fps")) > 0.0);
  CHECK(std::stod(JsonField(json, "video_to_screen_ms_p50")) > 0.0);
  const double lap_s = std::stod(JsonField(json, "lap_time_s"));
  cv::VideoCapture video(mp4.string(), cv::CAP_FFMPEG);
  REQUIRE(video.isOpened());
  int frames = 0;
  cv::Mat frame;
  while (video.read(frame)) ++frames;
  CHECK(frame.empty());
  CHECK(frames >= 25.0 * lap_s);
}

TEST_CASE("a person's keys drive the robot in the view's window, and releasing them stops it") {
  XServer x;
  const auto dir = test::ScratchDir("e2e-view-keys");
  Child run({Bin("haptel"), "run", "--operator", "person", "--interface", "keyboard", "--view", "window",
             "--time-limit", "10", "--track", "config/tracks/test-short.yaml", "--json", "--domain",
             std::to_string(test::UniqueDomain(32)), "--database", (dir / "runs.db").string(), "--vehicle-timeout",
             "5"});
  // The window is up and the vehicle answers once the first progress line shows.
  REQUIRE(test::WaitFor([&] {
    run.Pump();
    return run.err().find("distance") != std::string::npos;
  }, 60.0));
  REQUIRE(XDoTool({"search", "--sync", "--name", "Haptel", "windowfocus", "--sync"}) == 0);
  REQUIRE(XDoTool({"keydown", "Up"}) == 0);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  REQUIRE(XDoTool({"keyup", "Up"}) == 0);
  // F2: the run's second interface; the switch is recorded.
  REQUIRE(XDoTool({"key", "F2"}) == 0);
  const int code = run.Wait(60.0);
  INFO(run.out() << run.err());
  CHECK(code == 1);  // time limit: a lap not completed
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "time limit");
  CHECK(JsonField(json, "operator") == "person");
  CHECK(std::stod(JsonField(json, "distance_m")) > 0.5);
  CHECK(json.find("\"to\":\"cockpit\"") != std::string::npos);
  // The cockpit's physics world was built when it was asked for, and ran from then on.
  CHECK(run.err().find("physics world built for 'cockpit'") != std::string::npos);
  CHECK(std::stod(JsonField(json, "physics_rate_hz")) > 0.0);
  // The last progress line, seconds after the key came up: standing.
  CHECK(LastSpeed(run.err()) == Approx(0.0).margin(0.02));
}

TEST_CASE("Escape in the window aborts the run, stops the vehicle and keeps what was measured") {
  XServer x;
  const auto dir = test::ScratchDir("e2e-view-abort");
  Child run({Bin("haptel"), "run", "--operator", "person", "--interface", "keyboard", "--view", "window", "--track",
             "config/tracks/test-short.yaml", "--json", "--domain", std::to_string(test::UniqueDomain(33)),
             "--database", (dir / "runs.db").string(), "--vehicle-timeout", "5"});
  REQUIRE(test::WaitFor([&] {
    run.Pump();
    return run.err().find("distance") != std::string::npos;
  }, 60.0));
  const std::string json = test::EndWithEscape(run);
  CHECK(std::stoi(JsonField(json, "run_id")) >= 1);
  // Keys only, no cockpit asked for: no physics world, so no proxy hands
  // nobody holds pushing against the servo loop's force clamp.
  CHECK(std::stod(JsonField(json, "physics_rate_hz")) == 0.0);
  CHECK(run.err().find("physics world built") == std::string::npos);
  CHECK(json.find("\"servo_forces_clamped\":0") != std::string::npos);
}

TEST_CASE("a recording that cannot grow (as on a full disk) ends, is said on stderr, in the summary and the JSON, "
          "and the run exits 5") {
  const auto dir = test::ScratchDir("e2e-view-full");
  const auto mp4 = dir / "lap.mp4";
  // prlimit: no file this run writes may grow past the limit (a write past
  // it fails with EFBIG; haptel ignores SIGXFSZ). The database and the
  // picture stay below it; the MP4 of the lap does not.
  constexpr int kLimit = 192 * 1024;
  Child run({"/usr/bin/prlimit", "--fsize=" + std::to_string(kLimit) + ":", "--", Bin("haptel"), "run",
             "--operator", "auto", "--view", "none", "--record", mp4.string(), "--track",
             "config/tracks/test-short.yaml", "--json", "--quiet", "--domain", std::to_string(test::UniqueDomain(34)),
             "--database", (dir / "runs.db").string(), "--vehicle-timeout", "5"});
  const int code = run.Wait(180.0);
  INFO(run.out() << run.err());
  CHECK(code == 5);
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "completed");  // the lap itself went on
  CHECK(JsonField(json, "recorded") == "true");
  const std::string error = JsonField(json, "record_error");
  CHECK(error.find("cannot write " + mp4.string() + ": File too large") != std::string::npos);
  // Said once on stderr as it happened, and in the summary instead of "recorded to".
  const std::string said = "the operator's view is not recorded whole: cannot write " + mp4.string();
  const size_t first = run.err().find(said);
  CHECK(first != std::string::npos);
  CHECK(run.err().find(said, first + 1) == std::string::npos);
  CHECK(run.out().find("operator's view NOT recorded whole: cannot write " + mp4.string()) != std::string::npos);
  CHECK(run.out().find("operator's view recorded to") == std::string::npos);
  CHECK(std::filesystem::file_size(mp4) <= static_cast<uintmax_t>(kLimit));
}
