// The camera station on the link against a vehicle's camera faked in the
// test (its status, its video, its lease the vehicle's own CommandIntake):
// the station takes the free camera and aims it (the status and the frames
// say where it points; the command-to-picture latency is measured from the
// frames' command_seq); a second station is refused, naming the holder and
// since when, and takes the camera once the first releases it.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>

#include "haptel/core/clock.hpp"
#include "haptel/core/periodic_thread.hpp"
#include "haptel/core/process_identity.hpp"
#include "haptel/link/families.hpp"
#include "haptel/station/camera_station.hpp"
#include "haptel/vehicles/command_intake.hpp"
#include "test_env.hpp"

using namespace haptel;
using station::CameraStation;
using station::Role;

namespace {

constexpr double kDeg = 0.017453292519943295;
const CameraRange kRange{-170 * kDeg, 170 * kDeg, -80 * kDeg, 10 * kDeg, 10.0};

/// blimp1's surveillance camera, faked: a lease (the vehicle's CommandIntake),
/// the status at 20 Hz, a frame at 20 Hz taken where the camera points.
class FakeCamera {
 public:
  explicit FakeCamera(int domain) : participant_(Link(domain), "fake-vehicle") {
    status_ = std::make_unique<link::CameraStatusWriter>(
        participant_, link::CameraStatusTopic("blimp1"), link::CameraMessages::kStatusProfile);
    video_ = std::make_unique<link::VideoWriter>(
        participant_, link::VideoTopic("blimp1", "surveillance", false), link::Profile::kVideo);
    reader_ = std::make_unique<link::CameraCommandReader>(
        participant_, link::CameraCommandTopic("blimp1", "surveillance"),
        link::CameraMessages::kCommandProfile,
        [this](const msg::CameraCommand& cmd, const link::WriterId& writer) {
          CameraAim aim;
          const bool valid = link::CameraMessages::Decode(cmd, "surveillance", kRange, aim);
          intake_.Offer(valid, {writer, cmd.session(), cmd.operator_name().c_str(), cmd.release()},
                        cmd.seq(), cmd.sent_ns(), aim, MonotonicNs());
        });
    tick_ = std::make_unique<PeriodicThread>(
        PeriodicThread::Options{.name = "fake-camera", .rate_hz = 20.0},
        [this](int64_t now) { Tick(now); });
    tick_->Start();
  }
  ~FakeCamera() { tick_->Stop(); }

 private:
  static LinkConfig Link(int domain) {
    LinkConfig c;
    c.domain_id = domain;
    return c;
  }
  void Tick(int64_t now) {
    intake_.Poll(now);
    const vehicles::ReceivedCommand<CameraAim>& applied = intake_.applied();
    const CameraAim aim = applied.seq != 0 ? applied.command : CameraAim{};
    msg::CameraStatus status;
    status.seq(++seq_);
    status.stamp_ns(now);
    msg::CameraInfo pilot;
    pilot.name("pilot");
    pilot.driven(true);
    msg::CameraInfo c;
    c.name("surveillance");
    c.fov_deg(60.0f);
    c.pan_min(static_cast<float>(kRange.pan_min));
    c.pan_max(static_cast<float>(kRange.pan_max));
    c.tilt_min(static_cast<float>(kRange.tilt_min));
    c.tilt_max(static_cast<float>(kRange.tilt_max));
    c.zoom_max(static_cast<float>(kRange.zoom_max));
    c.pan(static_cast<float>(aim.pan));
    c.tilt(static_cast<float>(aim.tilt));
    c.zoom(static_cast<float>(aim.zoom));
    c.last_command_seq(applied.seq);
    c.commands_refused(intake_.refused());
    const vehicles::CommandOwnerInfo holder = intake_.owner();
    c.holder_session(holder.session);
    c.holder(holder.name);
    c.holder_writer(holder.writer.guid);
    c.held_since_wall_ns(holder.since_wall_ns);
    status.cameras({pilot, c});
    status_->Write(status);
    msg::VideoFrame frame;
    frame.seq(seq_);
    frame.capture_wall_ns(WallNs());
    frame.width(8);
    frame.height(8);
    frame.encoding("jpeg");
    frame.key_frame(true);
    frame.data(std::vector<uint8_t>(64, 0));
    frame.camera("surveillance");
    frame.pan(static_cast<float>(aim.pan));
    frame.tilt(static_cast<float>(aim.tilt));
    frame.zoom(static_cast<float>(aim.zoom));
    frame.fov_deg(static_cast<float>(ZoomedFovDeg(60.0, aim.zoom)));
    frame.command_seq(applied.seq);
    video_->Write(frame);
  }

  link::Participant participant_;
  vehicles::CommandIntake<CameraAim> intake_{vehicles::CommandOwner::kFreeAfter_s};
  uint64_t seq_ = 0;
  std::unique_ptr<link::CameraStatusWriter> status_;
  std::unique_ptr<link::VideoWriter> video_;
  std::unique_ptr<link::CameraCommandReader> reader_;
  std::unique_ptr<PeriodicThread> tick_;
};

station::StationOptions Options(int domain, const std::string& who) {
  station::StationOptions o;
  o.link.domain_id = domain;
  o.vehicle = "blimp1";
  o.camera = "surveillance";
  o.session = NewSessionId();
  o.operator_name = who;
  o.decode = false;
  return o;
}

}  // namespace

TEST_CASE(
    "a camera station takes a free camera and aims it; a second is refused, naming the holder and "
    "since when, and takes it once the first lets it go") {
  const int domain = test::UniqueDomain(383);
  FakeCamera vehicle(domain);
  auto eve = std::make_unique<CameraStation>(Options(domain, "haptel station, eve@lab2 pid 7"));
  const CameraAim aim{30 * kDeg, -10 * kDeg, 4.0};
  eve->Aim(aim);
  REQUIRE(test::WaitFor(
      [&] {
        const station::CameraNow now = eve->Now();
        return now.role == Role::kHolding && std::abs(now.applied.zoom - 4.0) < 1e-3 &&
               eve->Figures().picture_frames > 0 && eve->Figures().picture_aim.zoom > 3.99;
      },
      30.0));
  station::CameraNow now = eve->Now();
  CHECK(now.applied.pan == Approx(30 * kDeg).margin(1e-5));
  CHECK(now.applied.tilt == Approx(-10 * kDeg).margin(1e-5));
  CHECK(std::string(now.cameras) == "pilot, surveillance");
  CHECK(station::HolderLine(now, "blimp1", "surveillance", domain) ==
        "camera surveillance of blimp1 is yours");
  // The move was seen in a picture: its latency measured.
  REQUIRE(test::WaitFor([&] { return eve->Figures().command_to_picture_count > 0; }, 10.0));
  CHECK(eve->Figures().command_to_picture_ms_p50 > 0.0);
  CHECK(eve->Figures().picture_aim.pan == Approx(30 * kDeg).margin(1e-5));

  CameraStation bo(Options(domain, "haptel station, bo@lab3 pid 8"));
  bo.Aim({-90 * kDeg, 0.0, 1.0});
  REQUIRE(test::WaitFor([&] { return bo.Now().role == Role::kRefused; }, 30.0));
  // Its commands are refused: the camera stays where eve aimed it.
  REQUIRE(test::WaitFor([&] { return bo.Now().commands_refused > 5; }, 10.0));
  const std::string line = station::HolderLine(bo.Now(), "blimp1", "surveillance", domain);
  CHECK_THAT(line, Catch::StartsWith("camera surveillance of blimp1 is held by haptel station, "
                                     "eve@lab2 pid 7 since ") &&
                       Catch::EndsWith(" UTC"));
  CHECK(bo.Now().applied.pan == Approx(30 * kDeg).margin(1e-5));

  // Eve ends: she releases the camera, and bo takes it at once (well before eve's lease ran out).
  const int64_t released = MonotonicNs();
  eve.reset();
  REQUIRE(test::WaitFor([&] { return bo.Now().role == Role::kHolding; }, 30.0));
  REQUIRE(test::WaitFor([&] { return std::abs(bo.Now().applied.pan + 90 * kDeg) < 1e-4; }, 10.0));
  INFO("taken after " << NsToS(MonotonicNs() - released) << " s");
}

TEST_CASE("a station on a camera that is not there, or the driver's, says so") {
  const int domain = test::UniqueDomain(384);
  FakeCamera vehicle(domain);
  station::StationOptions rear = Options(domain, "x");
  rear.camera = "rear";
  CameraStation none(rear);
  station::StationOptions pilot = Options(domain, "x");
  pilot.camera = "pilot";
  CameraStation driven(pilot);
  REQUIRE(test::WaitFor(
      [&] { return none.Now().role == Role::kNoSuchCamera && driven.Now().role == Role::kDriven; },
      30.0));
  CHECK(station::HolderLine(none.Now(), "blimp1", "rear", domain) ==
        "blimp1 has no camera 'rear' (its cameras: pilot, surveillance)");
  CHECK_THAT(station::HolderLine(driven.Now(), "blimp1", "pilot", domain),
             Catch::Contains("is the driver's"));
  CHECK(driven.Figures().commands_sent == 0);  // nothing is ever sent to it
}
