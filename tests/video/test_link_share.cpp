// video::LinkShare: one link's capacity among a vehicle's cameras by
// priority (issue 38: the driven camera first, a floor for the next,
// nothing over the capacity), the capacity being the sum of the receivers'
// estimates (each receiver sees only its own stream).
#include <catch2/catch.hpp>
#include <cstdint>

#include "haptel/video/camera_streamer.hpp"

using haptel::video::LinkShare;

namespace {

constexpr int64_t kSecond_ns = 1'000'000'000;

/// Sends `kbps` from `slot` over the second before `now_ns` (so SentKbps says it).
void SendFor(LinkShare& share, int slot, uint32_t kbps, int64_t now_ns) {
  share.OnSent(slot, 1, now_ns - 2 * kSecond_ns);
  share.OnSent(slot, kbps * 1000 / 8, now_ns - kSecond_ns);
  share.OnSent(slot, 1, now_ns);
}

}  // namespace

TEST_CASE("LinkShare::Split: the first camera first, a floor for the next, nothing over",
          "[video]") {
  const LinkShare::Demand unbounded[2] = {{0, 0}, {0, 0}};
  uint32_t targets[2] = {0, 0};

  // 800 kbit/s: the pilot all but the surveillance camera's floor.
  LinkShare::Split(800, unbounded, 2, targets);
  CHECK(targets[0] == 800 - LinkShare::kFloor_kbps);
  CHECK(targets[1] == LinkShare::kFloor_kbps);

  // An H.264 pilot that uses at most 2000: the rest is the next camera's.
  const LinkShare::Demand bounded[2] = {{2000, 0}, {0, 0}};
  LinkShare::Split(3000, bounded, 2, targets);
  CHECK(targets[0] == 2000);
  CHECK(targets[1] == 1000);

  // A pilot sending 1000 of the 2850 it could have (its top JPEG rung)
  // takes a margin over what it sends; the rest goes on. Its target stays:
  // a ladder following what was sent would ratchet down to the floor.
  const LinkShare::Demand sending[2] = {{0, 1000}, {0, 400}};
  LinkShare::Split(3000, sending, 2, targets);
  CHECK(targets[0] == 3000 - LinkShare::kFloor_kbps);
  CHECK(targets[1] == 3000 - 1250);

  // Less than the floors: an equal share each, and never more than the link.
  const LinkShare::Demand three[3] = {};
  uint32_t three_targets[3] = {0, 0, 0};
  LinkShare::Split(300, three, 3, three_targets);
  CHECK(three_targets[0] == 100);
  CHECK(three_targets[1] == 100);
  CHECK(three_targets[2] == 100);
  for (const uint32_t capacity : {0U, 1U, 200U, 450U, 800U, 1500U, 3000U}) {
    LinkShare::Split(capacity, three, 3, three_targets);
    CHECK(three_targets[0] + three_targets[1] + three_targets[2] <= capacity);
    CHECK(three_targets[0] >= three_targets[1]);
  }
}

TEST_CASE(
    "LinkShare: the link's capacity is the sum of the receivers' estimates, given by priority",
    "[video]") {
  LinkShare share;
  // Added surveillance first: its priority, not its place, orders it.
  const int surveillance = share.Add(1);
  const int pilot = share.Add(0);
  const int64_t now = 100 * kSecond_ns;
  CHECK(share.TargetFor(pilot, now) == 0);  // no estimate yet: its own setting

  // On an 800 kbit/s link each receiver sees its own stream: 85 % of what
  // arrives, 300 and 380 (the surveillance camera had more of it).
  share.OnEstimate(pilot, 300, now);
  share.OnEstimate(surveillance, 380, now);
  SendFor(share, pilot, 350, now);
  SendFor(share, surveillance, 450, now);
  CHECK(share.CapacityKbps(now) == 680);
  const uint32_t pilot_target = share.TargetFor(pilot, now);
  const uint32_t surveillance_target = share.TargetFor(surveillance, now);
  // The pilot is given more than its own receiver's estimate: the link's
  // all but the floor; the surveillance camera what the pilot's 350 and a
  // margin leave, and together they take no more than the link.
  CHECK(pilot_target == 680 - LinkShare::kFloor_kbps);
  CHECK(surveillance_target == 680 - 437);  // 437: 1.25 x 350
  CHECK(pilot_target > surveillance_target);
  CHECK(437 + surveillance_target <= share.CapacityKbps(now));

  // Nobody watches the pilot any more (its estimate ages): the surveillance
  // camera has the link, and the pilot its own setting.
  const int64_t later = now + LinkShare::kFresh_ns;
  share.OnEstimate(surveillance, 900, later);
  CHECK(share.TargetFor(pilot, later) == 0);
  CHECK(share.CapacityKbps(later) == 900);
  SendFor(share, surveillance, 800, later);
  CHECK(share.TargetFor(surveillance, later) == 900);
}
