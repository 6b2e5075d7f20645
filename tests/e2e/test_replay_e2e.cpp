// End to end, haptel replay: the short-track lap test_e2e_lap recorded whole
// (haptel run --session, its view offscreen with --record; the ctest fixture
// e2e_lap) is drawn again into an MP4 whose frames match the live MP4's (SSIM
// by video::Ssim on both decoded by FFmpeg through OpenCV's videoio), and
// driven again on a simulated robot through the same gates; a recording
// killed mid-lap (SIGKILL) is read whole by haptel replay --view none, and
// recovered by haptel record --recover into a file the reference reader
// reads whole.
#include <signal.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <opencv2/videoio.hpp>
#include <regex>

#include "child.hpp"
#include "haptel/video/image_quality.hpp"
#include "mcap_reference.hpp"
#include "recorded_lap.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// `haptel run` recording a short-track lap whole, on the twin (what is
/// tested is the file, not the vehicle's reality), with its progress lines
/// every 2 s on stderr.
std::vector<std::string> RecordedLap(const std::filesystem::path& dir, int domain) {
  return {Bin("haptel"),
          "run",
          "--operator",
          "auto",
          "--view",
          "none",
          "--session",
          (dir / "lap.mcap").string(),
          "--track",
          "config/tracks/test-short.yaml",
          "--json",
          "--domain",
          std::to_string(domain),
          "--database",
          (dir / "runs.db").string(),
          "--vehicle-timeout",
          "5",
          "--reality",
          "none"};
}

}  // namespace

TEST_CASE(
    "a recorded lap replays into the live MP4's frames, and driven again passes the record's "
    "gates") {
  // test_e2e_lap's lap (the lab robot, seed 3), completed: ctest runs it first.
  const auto lap = test::RecordedLapDir();
  const auto session = lap / "sessions" / "lap.mcap";
  INFO("the lap test_e2e_lap records (ctest -R test_e2e_replay runs it first): " << lap);
  REQUIRE(std::filesystem::is_regular_file(session));
  REQUIRE(std::filesystem::is_regular_file(lap / "live.mp4"));
  const auto dir = test::ScratchDir("e2e-replay");

  Child replay({Bin("haptel"), "replay", session.string(), "--mp4", (dir / "replay.mp4").string()});
  const int replayed = replay.Wait(120.0);
  INFO(replay.out() << replay.err());
  REQUIRE(replayed == 0);
  // Every picture decodes, and every view frame's picture is found: the
  // replay keeps the pictures the live screen may still show (it lags its
  // receiver by up to 15 decoded frames, and shows a stale one until the
  // next key frame).
  static const std::regex read_line(
      R"(([0-9]+) view frames, [0-9]+ camera pictures( \(([0-9]+) frames' pictures not in the file, 0 pictures undecoded\))?)");
  std::smatch m;
  REQUIRE(std::regex_search(replay.out(), m, read_line));
  const int view_frames = std::stoi(m[1]);
  const int missing = m[3].matched ? std::stoi(m[3]) : 0;
  CHECK(view_frames > 30);
  CHECK(missing == 0);

  cv::VideoCapture live((lap / "live.mp4").string(), cv::CAP_FFMPEG);
  cv::VideoCapture again((dir / "replay.mp4").string(), cv::CAP_FFMPEG);
  REQUIRE(live.isOpened());
  REQUIRE(again.isOpened());
  cv::Mat a, b;
  int frames = 0;
  double worst = 1.0;
  int worst_at = -1;
  for (;;) {
    const bool got_live = live.read(a);
    const bool got_again = again.read(b);
    REQUIRE(got_live == got_again);  // as many frames in both
    if (!got_live) break;
    const double ssim = video::Ssim(a, b);
    if (ssim < worst) {
      worst = ssim;
      worst_at = frames;
    }
    ++frames;
  }
  INFO("frames " << frames << ", worst SSIM " << worst << " at frame " << worst_at);
  CHECK(frames > 30);
  CHECK(worst >= 0.95);

  Child drive({Bin("haptel"), "replay", session.string(), "--drive", "--domain",
               std::to_string(test::UniqueDomain(72)), "--json"});
  const int drove = drive.Wait(180.0);
  INFO(drive.out() << drive.err());
  CHECK(drove == 0);
  const std::string json = drive.LastLine();
  CHECK(JsonField(json, "recorded_gates") == JsonField(json, "gates_total"));
  CHECK(JsonField(json, "gates_passed") == JsonField(json, "recorded_gates"));
  CHECK(JsonField(json, "reproduced") == "true");
}

TEST_CASE("a session killed mid-lap is read by haptel replay") {
  const auto dir = test::ScratchDir("e2e-replay-killed");
  Child run(RecordedLap(dir, test::UniqueDomain(73)));
  // Mid-lap: past the first gate (the progress lines say), and a chunk
  // flushed since.
  REQUIRE(test::WaitForErr(run, "gates 1/", 120.0));
  const auto file = dir / "lap.mcap";
  const auto size_at_gate = std::filesystem::exists(file) ? std::filesystem::file_size(file) : 0;
  REQUIRE(test::WaitFor(
      [&] {
        run.Pump();
        return std::filesystem::exists(file) && std::filesystem::file_size(file) > size_at_gate;
      },
      30.0));
  ::kill(run.pid(), SIGKILL);
  const auto killed_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  run.Wait(30.0);

  Child replay({Bin("haptel"), "replay", file.string(), "--view", "none"});
  const int code = replay.Wait(60.0);
  INFO(replay.out() << replay.err());
  CHECK(code == 0);
  CHECK(replay.err().find("was not closed") != std::string::npos);
  CHECK(replay.out().find("replayed " + file.string()) != std::string::npos);
  CHECK(replay.out().find(" 0 view frames") == std::string::npos);

  // haptel record --recover writes a complete copy, which the reference
  // reader reads whole (indexes, summary, every CRC).
  const auto recovered = dir / "recovered.mcap";
  Child recover({Bin("haptel"), "record", "--recover", file.string(), recovered.string()});
  const int recover_code = recover.Wait(60.0);
  INFO(recover.out() << recover.err());
  REQUIRE(recover_code == 0);
  const std::string read = test::ReferenceRead(recovered, "--decode");
  INFO(read);
  CHECK(JsonField(read, "footer") == "true");
  CHECK(JsonField(read, "data_section_ok") == "true");
  CHECK(JsonField(read, "summary_ok") == "true");
  CHECK(JsonField(read, "failed") == "0");
  CHECK(std::stol(JsonField(read, "ok")) > 1000);
  CHECK(JsonField(read, "ok") == JsonField(read, "statistics_messages"));
  // Only the last second is lost: the recorder drains its rings every 10 ms
  // and closes a chunk every second (SessionFileOptions::flush_period_s),
  // so the last message kept is at most that second (plus a drain, and
  // 1.5 s for a loaded machine's scheduling) older than the kill.
  Child info({Bin("haptel"), "replay", "--info", recovered.string(), "--json"});
  REQUIRE(info.Wait(60.0) == 0);
  const double end_before_kill_s =
      static_cast<double>(killed_ns - std::stoll(JsonField(info.LastLine(), "end_ns"))) * 1e-9;
  INFO(info.out());
  CHECK(end_before_kill_s >= 0.0);
  CHECK(end_before_kill_s < 2.5);
}
