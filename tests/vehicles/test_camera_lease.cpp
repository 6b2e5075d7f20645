// The camera role (issue 38): one station at a time holds a camera, bound
// to its command writer; another is refused, counted, until the holder
// releases it or falls silent; the holder is named with since when; and a
// participant that holds a camera may not drive the vehicle, however free
// the vehicle is.
#include <catch2/catch.hpp>
#include <string>

#include "haptel/core/clock.hpp"
#include "haptel/vehicles/camera_lease.hpp"

using namespace haptel::vehicles;
using Verdict = CommandOwner::Verdict;

namespace {
constexpr int64_t kMs = 1'000'000;
haptel::link::WriterId Writer(uint8_t participant, uint8_t writer) {
  haptel::link::WriterId id;
  id.guid[0] = 0x01;
  id.guid[1] = 0x0f;
  id.guid[11] = participant;
  id.guid[15] = writer;
  return id;
}
}  // namespace

TEST_CASE(
    "camera leases: the first station holds the camera, a second is refused until the "
    "first releases it or falls silent") {
  CameraLeases leases(2);
  const CommandSender eve{Writer(1, 3), 11, "haptel station, eve@lab2 pid 7", false};
  const CommandSender bo{Writer(2, 3), 22, "haptel station, bo@lab3 pid 8", false};
  CHECK(leases.Holder(1, 0).writer.empty());
  const int64_t before = haptel::WallNs();
  CHECK(leases.Admit(1, eve, 10 * kMs) == Verdict::kNewOwner);
  CHECK(leases.Admit(1, eve, 20 * kMs) == Verdict::kOwner);
  const CommandOwnerInfo holder = leases.Holder(1, 20 * kMs);
  CHECK(holder.writer == Writer(1, 3));
  CHECK(std::string(holder.name) == "haptel station, eve@lab2 pid 7");
  CHECK(holder.since_wall_ns >= before);
  CHECK(holder.since_wall_ns <= haptel::WallNs());
  // The other camera is another lease.
  CHECK(leases.Holder(0, 20 * kMs).writer.empty());
  CHECK(leases.Admit(0, bo, 20 * kMs) == Verdict::kNewOwner);

  CHECK(leases.Admit(1, bo, 30 * kMs) == Verdict::kRefused);
  CHECK(leases.Admit(1, {Writer(2, 3), 11, "copies eve's session", false}, 31 * kMs) ==
        Verdict::kRefused);
  CHECK(leases.Refused(1) == 2);
  CHECK(leases.Refused(0) == 0);

  // Released: free at once, and said so.
  CHECK(leases.Admit(1, {Writer(1, 3), 11, "", true}, 40 * kMs) == Verdict::kOwner);
  CHECK(leases.Holder(1, 40 * kMs).writer.empty());
  CHECK(leases.Admit(1, bo, 41 * kMs) == Verdict::kNewOwner);
  // Silent past the lease: nobody holds it, and the next station takes it.
  const int64_t silent = 41 * kMs + haptel::SToNs(CommandOwner::kFreeAfter_s) + kMs;
  CHECK(leases.Holder(1, silent).writer.empty());
  CHECK(leases.Admit(1, eve, silent) == Verdict::kNewOwner);
  CHECK(leases.Holder(1, silent).writer == Writer(1, 3));
}

TEST_CASE(
    "camera leases bar a holding station's participant from driving, however free the "
    "vehicle is") {
  CameraLeases leases(1);
  CommandIntake<int> driving(0.25);
  driving.SetBar(&leases);
  const CommandSender station_camera{Writer(1, 3), 11, "haptel station, eve", false};
  const CommandSender station_driving{Writer(1, 4), 11, "haptel station, eve", false};
  const CommandSender pilot{Writer(2, 3), 22, "haptel run, ana", false};
  CHECK(leases.Admit(0, station_camera, 10 * kMs) == Verdict::kNewOwner);
  // Another writer of the station's participant: barred, counted, and it does not take the vehicle.
  CHECK_FALSE(driving.Offer(true, station_driving, 1, 0, 1, 11 * kMs));
  CHECK(driving.refused() == 1);
  CHECK(driving.owner().writer.empty());
  CHECK(driving.Offer(true, pilot, 1, 0, 2, 12 * kMs));
  // Once the station let the camera go, its participant is nobody special.
  CHECK(leases.Admit(0, {Writer(1, 3), 11, "", true}, 13 * kMs) == Verdict::kOwner);
  CHECK_FALSE(leases.Bars(station_driving.writer, 14 * kMs));
  CHECK_THROWS_AS(CameraLeases(CameraLeases::kMaxCameras + 1), std::invalid_argument);
}
