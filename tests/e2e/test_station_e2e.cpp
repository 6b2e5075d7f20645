// End to end, the camera station (issue 38; thesis 8.2.1's Surveillance
// Control Room): `haptel station` started on its own beside a simulated
// blimp's `haptel-vehicle` pans, tilts and zooms the surveillance camera
// (the vehicle's status and its pictures say so), records it, and never
// drives (the blimp's driving commands stay unheard); a second station
// asking for the held camera is refused with one line naming the holder and
// since when; a participant that holds the camera is refused the driving
// commands, however free the blimp is; and the same secured, the station a
// `camera-surveillance` identity of `haptel security init`. The station
// shows the blimp's state (its JSON and its log line); `haptel record
// --domain` beside records the camera topics, each decoded by its schema;
// a holder that falls silent (SIGSTOP) is released by the vehicle's lease
// and a new station takes the camera.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "child.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/participant.hpp"
#include "haptel/link/topic.hpp"
#include "mcap_reference.hpp"
#include "test_env.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

/// The simulated blimp with both cameras of the thesis on `domain`, up.
std::unique_ptr<Child> StartBlimp(int domain, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> argv{Bin("haptel-vehicle"),
                                "--config",
                                "config/vehicles/sim-blimp-surveillance.yaml",
                                "--track",
                                "config/tracks/blimp-hop.yaml",
                                "--name",
                                "blimp1",
                                "--reality",
                                "none",
                                "--domain",
                                std::to_string(domain)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  auto blimp = std::make_unique<Child>(argv);
  REQUIRE(test::WaitForErr(*blimp, " up on domain", 30.0));
  return blimp;
}

/// `haptel station` on `domain` without a window, plus `extra`.
std::vector<std::string> Station(int domain, const std::vector<std::string>& extra) {
  std::vector<std::string> argv{Bin("haptel"),         "station", "--vehicle", "blimp1", "--camera",
                                "surveillance",        "--view",  "none",      "--json", "--domain",
                                std::to_string(domain)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

/// The station's JSON line aimed at pan 30°, tilt -10°, zoom 4: the
/// vehicle applied it and its last picture was taken so.
void CheckAimed(const std::string& json) {
  CHECK(JsonField(json, "held") == "true");
  CHECK(std::stod(JsonField(json, "pan_deg")) == Approx(30.0).margin(0.1));
  CHECK(std::stod(JsonField(json, "tilt_deg")) == Approx(-10.0).margin(0.1));
  CHECK(std::stod(JsonField(json, "zoom")) == Approx(4.0).margin(0.01));
  CHECK(std::stod(JsonField(json, "picture_zoom")) == Approx(4.0).margin(0.01));
  CHECK(std::stod(JsonField(json, "picture_pan_deg")) == Approx(30.0).margin(0.1));
  CHECK(std::stoull(JsonField(json, "video_frames")) > 0);
  CHECK(std::stoull(JsonField(json, "command_to_picture_count")) > 0);
  // The blimp's state, through the family its status names.
  CHECK(JsonField(json, "vehicle_states") == "true");
  CHECK_THAT(JsonField(json, "vehicle_line"),
             Catch::StartsWith("blimp1 x ") && Catch::Contains(" alt ") && Catch::Contains(" m/s"));
}

}  // namespace

TEST_CASE(
    "a camera station pans, tilts and zooms the blimp's surveillance camera and records it; a "
    "second is refused the held camera, naming the holder; neither drives") {
  const int domain = test::UniqueDomain(380);
  const auto dir = test::ScratchDir("e2e-station");
  const auto blimp = StartBlimp(domain);
  // Recorded on the side, as `ros2 bag record` would: the camera topics too.
  const auto side = dir / "side.mcap";
  Child recorder({Bin("haptel"), "record", "--domain", std::to_string(domain), "--vehicle",
                  "blimp1", side.string()});
  REQUIRE(test::WaitForErr(recorder, "recording haptel/blimp1/cameras", 30.0));
  // The blimp's own state, heard beside the stations: its driving commands.
  LinkConfig link;
  link.domain_id = domain;
  link::Participant participant(link, "test");
  std::atomic<uint64_t> driving_heard{0};
  std::atomic<bool> failsafe_always{true};
  std::atomic<int> states{0};
  std::atomic<uint64_t> refused{0};
  std::atomic<uint64_t> received{0};
  link::BlimpStateReader state(participant, link::TopicName("blimp1", "state"),
                               link::Profile::kState, [&](const msg::BlimpState& s) {
                                 driving_heard.store(s.commands_received() + s.commands_refused());
                                 refused.store(s.commands_refused());
                                 received.store(s.commands_received());
                                 if (!s.failsafe()) failsafe_always.store(false);
                                 states.fetch_add(1);
                               });

  Child first(Station(
      domain, {"--aim", "30,-10,4", "--time-limit", "12", "--record",
               (dir / "surveillance.mp4").string(), "--session", (dir / "station.mcap").string()}));
  REQUIRE(test::WaitForErr(first, "camera surveillance of blimp1 is yours", 30.0));
  CHECK(test::WaitForErr(recorder, "recording haptel/blimp1/camera/surveillance", 30.0));
  // Asks while the first holds the camera, and ends before the first lets it go.
  Child second(Station(domain, {"--time-limit", "5"}));
  const int second_code = second.Wait(60.0);
  INFO("second:\n" << second.out() << second.err());
  CHECK(second_code == 1);
  CHECK(JsonField(second.LastLine(), "outcome") == "refused");
  CHECK(JsonField(second.LastLine(), "held") == "false");
  CHECK(second.err().find("camera surveillance of blimp1 is held by haptel station, ") !=
        std::string::npos);
  CHECK(second.err().find(" UTC") != std::string::npos);  // since when
  CHECK(second.err().find(", last heard ") != std::string::npos);

  const int code = first.Wait(60.0);
  INFO("first:\n" << first.out() << first.err());
  REQUIRE(code == 0);
  const std::string json = first.LastLine();
  CHECK(JsonField(json, "outcome") == "time limit");
  CheckAimed(json);
  CHECK(std::filesystem::file_size(dir / "surveillance.mp4") > 10000);
  CHECK(first.out().find("session file") != std::string::npos);
  CHECK(JsonField(json, "saved") == "true");  // the session file's
  // Without a window, its log line says where the blimp is.
  CHECK(first.err().find("blimp1 x ") != std::string::npos);

  // The side recording: the station's commands, the cameras' status and
  // the surveillance camera's video, each message decoded by its schema.
  kill(recorder.pid(), SIGINT);
  const int recorded = recorder.Wait(30.0);
  INFO("recorder:\n" << recorder.out() << recorder.err());
  REQUIRE(recorded == 0);
  const std::string read = test::ReferenceRead(side, "--decode");
  INFO(read);
  CHECK(JsonField(read, "footer") == "true");
  CHECK(JsonField(read, "failed") == "0");
  CHECK(std::stol(JsonField(read, "haptel/blimp1/camera/surveillance")) > 0);
  CHECK(std::stol(JsonField(read, "haptel/blimp1/cameras")) > 0);
  CHECK(std::stol(JsonField(read, "haptel/blimp1/video/surveillance")) > 0);
  // Nobody drove the blimp: no driving command reached it, and it stayed at neutral.
  CHECK(states.load() > 0);
  CHECK(driving_heard.load() == 0);
  CHECK(failsafe_always.load());

  // A participant that holds the camera may not drive, however free the blimp is: this test's
  // own, steering the camera and sending driving commands beside.
  link::CameraCommandWriter camera(participant, link::CameraCommandTopic("blimp1", "surveillance"),
                                   link::Profile::kCommand);
  link::BlimpCommandWriter drive(participant, link::TopicName("blimp1", "command"),
                                 link::Profile::kCommand);
  msg::CameraCommand aim;
  aim.camera("surveillance");
  aim.zoom(2.0f);
  msg::BlimpCommand power;
  power.power(0.5f);
  REQUIRE(test::WaitFor(
      [&] {
        aim.seq(aim.seq() + 1);
        camera.Write(aim);
        if (aim.seq() > 20) {  // the camera held for a while first
          power.seq(power.seq() + 1);
          drive.Write(power);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        return refused.load() > 20;
      },
      30.0));
  CHECK(received.load() == 0);

  // A holder that falls silent (stopped, not ended: no release) is
  // released by the vehicle's lease (2 s without its commands), and a new
  // station takes the camera.
  Child silent(Station(domain, {"--aim", "-20,0,2", "--time-limit", "60"}));
  REQUIRE(test::WaitForErr(silent, "camera surveillance of blimp1 is yours", 30.0));
  kill(silent.pid(), SIGSTOP);
  Child next(Station(domain, {"--time-limit", "60"}));
  const bool taken = test::WaitForErr(next, "camera surveillance of blimp1 is yours", 30.0);
  kill(silent.pid(), SIGCONT);
  kill(next.pid(), SIGINT);
  kill(silent.pid(), SIGINT);
  CHECK(next.Wait(30.0) == 0);
  INFO("next:\n" << next.out() << next.err());
  CHECK(taken);
  CHECK(JsonField(next.LastLine(), "held") == "true");
  CHECK(silent.Wait(30.0) == 0);
}

TEST_CASE(
    "secured: the station is identity camera-surveillance; it steers the camera of a secured "
    "blimp") {
  const int domain = test::UniqueDomain(381);
  const auto dir = test::ScratchDir("e2e-station-secured");
  const auto security = dir / "deployment";
  {
    Child init({Bin("haptel"), "security", "init", security.string(), "--vehicles", "blimp1",
                "--cameras", "surveillance", "--days", "2"});
    INFO(init.out() << init.err());
    REQUIRE(init.Wait(120.0) == 0);
    CHECK(init.out().find("camera stations camera-surveillance") != std::string::npos);
  }
  const auto blimp = StartBlimp(domain, {"--security", security.string()});
  Child station(Station(
      domain, {"--aim", "30,-10,4", "--time-limit", "12", "--security", security.string()}));
  const int code = station.Wait(90.0);
  INFO(station.out() << station.err());
  REQUIRE(code == 0);
  CheckAimed(station.LastLine());
}
