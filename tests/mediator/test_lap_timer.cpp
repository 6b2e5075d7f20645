#include <catch2/catch.hpp>

#include "haptel/mediator/lap_timer.hpp"

using namespace haptel;
using namespace haptel::mediator;

namespace {
const Track& ShortTrack() {
  static const Track track(LoadTrack("config/tracks/test-short.yaml"));
  return track;
}

/// Drives along the centre line from `from` to `to` (arc length, m), offset
/// sideways by `offset` (m, left positive), at `speed` m/s, updating the timer
/// every 20 ms. Returns the time reached.
double Follow(LapTimer& lap, const Track& track, double t, double from, double to,
              double offset = 0.0, double speed = 0.25) {
  for (double s = from; s <= to; s += speed * 0.02) {
    const Vec2 tangent = track.TangentAt(s);
    const Vec2 normal(-tangent.y(), tangent.x());
    lap.Update(t, track.PointAt(s) + normal * offset);
    t += 0.02;
  }
  return t;
}
}  // namespace

TEST_CASE("a clean lap passes every gate in order and times the lap from line to line") {
  const Track& track = ShortTrack();
  LapTimer lap(track);
  const double start = -track.config().start_behind;
  Follow(lap, track, 0.0, start, track.length() + 0.2);
  REQUIRE(lap.completed());
  CHECK(lap.gates_passed() == lap.gates_total());
  CHECK(lap.gates_missed() == 0);
  // Constant speed: the lap takes length / speed.
  CHECK(lap.lap_time_s() == Approx(track.length() / 0.25).margin(0.05));
  // Splits in order, at the gates' distances.
  for (const GateSplit& split : lap.splits()) {
    CHECK(split.passed);
    CHECK(split.split_s == Approx(track.gates()[split.gate].along / 0.25).margin(0.05));
  }
}

TEST_CASE("the lap does not start before the start line is crossed") {
  const Track& track = ShortTrack();
  LapTimer lap(track);
  Follow(lap, track, 0.0, -track.config().start_behind, -0.05);
  CHECK_FALSE(lap.started());
  CHECK(lap.lap_time_s() == 0.0);
}

TEST_CASE("crossing a gate line outside the posts counts as missed, not passed") {
  const Track& track = ShortTrack();
  LapTimer lap(track);
  const double g0 = track.gates()[0].along;
  double t = Follow(lap, track, 0.0, -0.3, g0 - 0.1);
  // Swing outside the right post (posts at +-0.2 m, post radius 0.03).
  t = Follow(lap, track, t, g0 - 0.1, g0 + 0.1, -0.26);
  t = Follow(lap, track, t, g0 + 0.1, track.length() + 0.2);
  REQUIRE(lap.completed());
  CHECK(lap.gates_missed() == 1);
  CHECK(lap.gates_passed() == lap.gates_total() - 1);
  CHECK_FALSE(lap.splits()[0].passed);
  CHECK(lap.splits()[0].split_s > 0.0);
}

TEST_CASE("backing over the start line does not finish the lap") {
  const Track& track = ShortTrack();
  LapTimer lap(track);
  double t = Follow(lap, track, 0.0, -0.3, 0.1);
  REQUIRE(lap.started());
  // Back up over the line and forward again.
  for (double s = 0.1; s >= -0.1; s -= 0.005) lap.Update(t += 0.02, track.PointAt(s));
  t = Follow(lap, track, t, -0.1, 0.2);
  CHECK_FALSE(lap.completed());
  CHECK(lap.next_gate() == 0);
}

TEST_CASE("gates must be taken in order: driving backwards through a gate does not count") {
  const Track& track = ShortTrack();
  LapTimer lap(track);
  const double g0 = track.gates()[0].along;
  double t = Follow(lap, track, 0.0, -0.3, g0 + 0.1);
  REQUIRE(lap.next_gate() == 1);
  for (double s = g0 + 0.1; s >= g0 - 0.1; s -= 0.005) lap.Update(t += 0.02, track.PointAt(s));
  t = Follow(lap, track, t, g0 - 0.1, g0 + 0.1);
  CHECK(lap.next_gate() == 1);
  CHECK(lap.gates_passed() == 1);
}

TEST_CASE("obstacle touches count distinct contact events") {
  const Track& track = ShortTrack();
  LapTimer lap(track, 0.3);
  lap.UpdateContact(1.0, true);
  lap.UpdateContact(1.02, true);
  lap.UpdateContact(1.04, false);
  lap.UpdateContact(1.06, true);  // chatter: clear for only 20 ms
  lap.UpdateContact(1.08, false);
  CHECK(lap.obstacles_touched() == 1);
  lap.UpdateContact(2.0, true);  // a new contact after a clear second
  lap.UpdateContact(2.5, false);
  CHECK(lap.obstacles_touched() == 2);
}
