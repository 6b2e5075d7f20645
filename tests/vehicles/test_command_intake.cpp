#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <vector>

#include "alloc_counter.hpp"
#include "haptel/vehicles/command_intake.hpp"
#include "haptel/vehicles/command_watchdog.hpp"

using namespace haptel::vehicles;

TEST_CASE("the watchdog is expired until the first command") {
  CommandWatchdog w(0.25);
  CHECK(w.Expired(0));
  CHECK(w.Expired(1'000'000'000));
}

TEST_CASE("the watchdog expires exactly after the timeout without commands") {
  constexpr int64_t kMs = 1'000'000;
  CommandWatchdog w(0.25);
  w.Feed(1000 * kMs);
  CHECK_FALSE(w.Check(1000 * kMs));
  CHECK_FALSE(w.Check(1250 * kMs));  // exactly at the timeout: still fresh
  CHECK(w.Check(1251 * kMs));
  CHECK(w.trips() == 1);
  CHECK(w.Check(1400 * kMs));
  CHECK(w.trips() == 1);  // one trip per silence, not per check
  w.Feed(1500 * kMs);
  CHECK_FALSE(w.Check(1500 * kMs));
  CHECK(w.Check(1800 * kMs));
  CHECK(w.trips() == 2);
}

TEST_CASE("the watchdog rejects a non-positive timeout") {
  CHECK_THROWS_AS(CommandWatchdog(0.0), std::invalid_argument);
  CHECK_THROWS_AS(CommandWatchdog(-1.0), std::invalid_argument);
}

TEST_CASE(
    "command intake: malformed and stale commands are counted and dropped, the newest is applied") {
  CommandIntake<int> in(0.25);
  const int64_t ms = 1'000'000;
  CHECK(in.Poll(0));  // nothing yet: expired
  CHECK(in.AppliedAgeNs(5 * ms) == 0);
  CHECK_FALSE(in.Offer(false, {}, 1, 0, 7, 10 * ms));  // fails its range check
  CHECK(in.Offer(true, {}, 2, 0, 8, 20 * ms));
  CHECK_FALSE(in.Offer(true, {}, 2, 0, 9, 30 * ms));  // not newer
  CHECK_FALSE(in.Offer(true, {}, 1, 0, 9, 40 * ms));  // older: reordered
  CHECK_FALSE(in.Poll(50 * ms));
  CHECK(in.applied().command == 8);
  CHECK(in.applied().seq == 2);
  CHECK(in.AppliedAgeNs(50 * ms) == 30 * ms);
  CHECK(in.accepted() == 1);
  CHECK(in.malformed() == 1);
  CHECK(in.stale() == 2);
  // Silence past the timeout: expired, one trip.
  CHECK(in.Poll(300 * ms));
  CHECK(in.watchdog_expired());
  CHECK(in.watchdog_trips() == 1);
  // A restarted sender (sequence from 1 again) is taken once the last
  // command is older than the timeout.
  CHECK(in.Offer(true, {}, 1, 0, 5, 400 * ms));
  CHECK_FALSE(in.Poll(410 * ms));
  CHECK(in.applied().command == 5);
}

namespace {
/// A DDS writer's identity: participant `p`, writer `w`.
haptel::link::WriterId Writer(uint8_t p, uint8_t w) {
  haptel::link::WriterId id;
  id.guid[0] = 0x01;
  id.guid[1] = 0x0f;
  id.guid[11] = p;
  id.guid[15] = w;
  return id;
}
}  // namespace

TEST_CASE(
    "command intake: one operator's writer at a time; a release or the owner's silence frees the "
    "vehicle") {
  CommandIntake<int> in(0.25);
  const int64_t ms = 1'000'000;
  const CommandSender ana{Writer(1, 3), 11, "ana's run", false};
  const CommandSender bo{Writer(2, 3), 22, "bo's run", false};
  CHECK(in.owner().session == 0);
  CHECK(in.owner().writer.empty());
  // The first writer takes the vehicle; the state can name it.
  CHECK(in.Offer(true, ana, 1, 0, 1, 10 * ms));
  CHECK(in.owner().session == 11);
  CHECK(in.owner().writer == Writer(1, 3));
  CHECK(std::string(in.owner().name) == "ana's run");
  // Another writer's commands are refused and counted, newer or not.
  CHECK_FALSE(in.Offer(true, bo, 50, 0, 2, 20 * ms));
  CHECK(in.Offer(true, ana, 2, 0, 3, 30 * ms));
  CHECK_FALSE(in.Offer(true, bo, 51, 0, 4, 40 * ms));
  CHECK(in.refused() == 2);
  CHECK(in.stale() == 0);
  CHECK_FALSE(in.Poll(45 * ms));
  CHECK(in.applied().command == 3);
  // A malformed command is malformed whoever sends it; it does not claim.
  CHECK_FALSE(in.Offer(false, bo, 52, 0, 5, 50 * ms));
  CHECK(in.malformed() == 1);
  CHECK(in.owner().session == 11);

  // The owner's last command releases it: the next writer takes it at
  // once, its sequence from 1 (not stale against the last owner's).
  CHECK(in.Offer(true, {Writer(1, 3), 11, "ana's run", true}, 3, 0, 0, 60 * ms));
  CHECK(in.owner().session == 0);
  CHECK(in.owner().writer.empty());
  CHECK(in.Offer(true, bo, 1, 0, 6, 61 * ms));
  CHECK(in.owner().session == 22);
  CHECK(std::string(in.owner().name) == "bo's run");
  CHECK(in.stale() == 0);

  // An owner that falls silent keeps the vehicle through a link's hiccup...
  CHECK_FALSE(in.Offer(true, ana, 1, 0, 7, 61 * ms + haptel::SToNs(1.0)));
  CHECK(in.owner().session == 22);
  CHECK(in.OwnerAt(61 * ms + haptel::SToNs(1.0)).session == 22);
  CHECK(in.owner_heard_wall_ns() > 0);  // its last command, heard
  // ...is named no more once its lease ran out, though nobody took it yet
  // (a camera's status stops naming a silent holder)...
  CHECK(in.OwnerAt(62 * ms + haptel::SToNs(CommandOwner::kFreeAfter_s)).writer.empty());
  CHECK(in.OwnerAt(62 * ms + haptel::SToNs(CommandOwner::kFreeAfter_s)).session == 0);
  // ...and loses it after CommandOwner::kFreeAfter_s.
  CHECK(in.Offer(true, ana, 1, 0, 8, 62 * ms + haptel::SToNs(CommandOwner::kFreeAfter_s)));
  CHECK(in.owner().session == 11);
  CHECK(in.refused() == 3);
}

TEST_CASE(
    "command intake: a stranger naming the owner's session is refused, its commands and its "
    "release") {
  // The session is in every state the vehicle publishes: anyone on the
  // domain can copy it. The owner is its writer, which nobody else has.
  CommandIntake<int> in(0.25);
  const int64_t ms = 1'000'000;
  const CommandSender ana{Writer(1, 3), 11, "ana's run", false};
  const CommandSender stranger{Writer(9, 3), 11, "ana's run", false};
  CHECK(in.Offer(true, ana, 1, 0, 1, 10 * ms));
  // Newer sequence numbers than the owner's, the owner's session and name: refused.
  CHECK_FALSE(in.Offer(true, stranger, 1'000'000'000, 0, -1, 20 * ms));
  CHECK_FALSE(in.Offer(true, {Writer(9, 3), 11, "ana's run", true}, 1'000'000'001, 0, 0, 30 * ms));
  CHECK(in.refused() == 2);
  CHECK(in.owner().writer == Writer(1, 3));
  // The owner drives on, its sequence unbroken (nothing of the stranger's is stale against it).
  CHECK(in.Offer(true, ana, 2, 0, 2, 40 * ms));
  CHECK(in.stale() == 0);
  CHECK_FALSE(in.Poll(45 * ms));
  CHECK(in.applied().command == 2);
  // Another writer of the owner's own participant is not the owner either.
  CHECK_FALSE(in.Offer(true, {Writer(1, 4), 11, "ana's run", false}, 3, 0, 3, 50 * ms));
  CHECK(in.refused() == 3);
}

TEST_CASE("command intake: ownership allocates nothing on the DDS thread", "[alloc]") {
  CommandIntake<int> in(0.25);
  const CommandSender ana{Writer(1, 3), 11, "ana's run", false};
  const CommandSender bo{Writer(2, 3), 22, "bo's run", false};
  in.Offer(true, ana, 1, 0, 1, 1);
  const uint64_t before = haptel::test::ThreadAllocations();
  for (uint64_t i = 2; i < 1000; ++i) {
    in.Offer(true, ana, i, 0, 1, static_cast<int64_t>(i) * 1000);
    in.Offer(true, bo, i, 0, 1, static_cast<int64_t>(i) * 1000);
    if (i % 100 == 0) {
      in.Offer(true, {Writer(1, 3), 11, "ana's run", true}, i, 0, 0,
               static_cast<int64_t>(i) * 1000 + 1);
    }
  }
  CHECK(haptel::test::ThreadAllocations() == before);
}

TEST_CASE(
    "control step: nominal first, then the time since the last tick, a starved thread's whole "
    "delay, at most 1 s") {
  int64_t last = 0;
  CHECK(ControlStep(last, 1'000'000'000, 200.0) == Approx(0.005));
  CHECK(ControlStep(last, 1'010'000'000, 200.0) == Approx(0.010));
  // 200 ms late (a loaded machine): the world moved on for all of it.
  CHECK(ControlStep(last, 1'210'000'000, 200.0) == Approx(0.200));
  CHECK(ControlStep(last, 3'000'000'000, 200.0) == Approx(kMaxControlStep_s));
}

namespace {
/// A vehicle's cameras' intakes as its driving bar (what the vehicle node
/// does over its steerable cameras).
struct CameraHolders : DrivingBar {
  std::vector<const CommandIntake<int>*> cameras;
  bool Bars(const haptel::link::WriterId& writer, int64_t now_ns) const override {
    for (const auto* c : cameras) {
      if (c->HeldByParticipantOf(writer, now_ns)) return true;
    }
    return false;
  }
};
}  // namespace

TEST_CASE(
    "the camera role: a camera's holder is named with since when; a participant that holds a "
    "camera may not drive, however free the vehicle is, until it lets the camera go") {
  const int64_t ms = 1'000'000;
  CommandIntake<int> camera(0.25);
  CommandIntake<int> driving(0.25);
  CameraHolders holders;
  holders.cameras = {&camera};
  driving.SetBar(&holders);
  const CommandSender station_camera{Writer(1, 3), 11, "haptel station, eve", false};
  const CommandSender station_driving{Writer(1, 4), 11, "haptel station, eve", false};
  const CommandSender pilot{Writer(2, 3), 22, "haptel run, ana", false};

  const int64_t before = haptel::WallNs();
  CHECK(camera.Offer(true, station_camera, 1, 0, 1, 10 * ms));
  CHECK(camera.owner().since_wall_ns >= before);
  CHECK(camera.owner().since_wall_ns <= haptel::WallNs());
  // Another writer of the station's participant: barred, counted, and it does not take the vehicle.
  CHECK_FALSE(driving.Offer(true, station_driving, 1, 0, 1, 11 * ms));
  CHECK(driving.refused() == 1);
  CHECK(driving.owner().writer.empty());
  CHECK(driving.Offer(true, pilot, 1, 0, 2, 12 * ms));

  // Silent past its lease, the station holds nothing, and bars nothing.
  const int64_t silent = 10 * ms + haptel::SToNs(CommandOwner::kFreeAfter_s) + ms;
  CHECK(camera.HeldByParticipantOf(station_driving.writer, 11 * ms));
  CHECK_FALSE(camera.HeldByParticipantOf(station_driving.writer, silent));
  CHECK_FALSE(camera.HeldByParticipantOf(pilot.writer, 11 * ms));
  // Released: at once.
  CHECK(camera.Offer(true, station_camera, 2, 0, 2, 20 * ms));
  CHECK(camera.Offer(true, {Writer(1, 3), 11, "", true}, 3, 0, 2, 21 * ms));
  CHECK_FALSE(holders.Bars(station_driving.writer, 22 * ms));
}
