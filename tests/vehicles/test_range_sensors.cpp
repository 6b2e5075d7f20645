// The simulated robot's range sensors against a known geometry: a straight
// corridor 1 m wide (walls at y = ±0.5 along its first leg) with a gate whose
// posts stand at (2, ±0.3), radius 0.04.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/vehicles/range_sensors.hpp"
#include "haptel/vehicles/sim_robot.hpp"

using namespace haptel;
using namespace haptel::vehicles;

namespace {
TrackConfig Corridor() {
  TrackConfig t;
  t.name = "corridor";
  t.centerline = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  t.corridor_width = 1.0;
  t.post_radius = 0.04;
  t.gates = {{2.0, 0.6}};
  return t;
}
Vec2 Direction(double angle) { return {std::cos(angle), std::sin(angle)}; }
}  // namespace

TEST_CASE("a ray reads the distance to the first wall or post it meets") {
  const Track track(Corridor());
  // Straight left and right: the walls, 0.5 m away.
  CHECK(CastRay(track, {1.0, 0.0}, Direction(std::numbers::pi / 2), 1.5) == Approx(0.5));
  CHECK(CastRay(track, {1.0, 0.1}, Direction(-std::numbers::pi / 2), 1.5) == Approx(0.6));
  // At 45° to the right wall: 0.5·√2.
  CHECK(CastRay(track, {1.0, 0.0}, Direction(-std::numbers::pi / 4), 1.5) ==
        Approx(0.5 * std::sqrt(2.0)));
  // At the left post's centre: its centre's distance less its radius.
  const Vec2 post(2.0, 0.3);
  const Vec2 to_post = post - Vec2(1.0, 0.0);
  CHECK(CastRay(track, {1.0, 0.0}, to_post.normalized(), 1.5) == Approx(to_post.norm() - 0.04));
  // Between the posts and along the corridor: nothing within 1.5 m reads 1.5 exactly.
  CHECK(CastRay(track, {1.0, 0.0}, Direction(0.0), 1.5) == 1.5);
  // A post nearer than a wall behind it hides the wall.
  CHECK(CastRay(track, {2.0, 0.0}, Direction(std::numbers::pi / 2), 1.5) == Approx(0.3 - 0.04));
}

TEST_CASE("the simulated robot publishes its scan, laid out as configured") {
  const Track track(Corridor());
  VehicleConfig config;
  config.range_sensors = {
      .beams = 31, .fov_deg = 180.0, .max_range = 1.5, .noise_sd = 0.0, .seed = 1};
  SimRobot robot(track, config);
  robot.Place(1.0, 0.0, 0.0);
  const RangeScan scan = robot.State().ranges;
  REQUIRE(scan.count == 31);
  CHECK(scan.angle_min == Approx(-std::numbers::pi / 2));
  CHECK(scan.angle_increment == Approx(std::numbers::pi / 30));
  CHECK(scan.range_max == 1.5);
  CHECK(scan.ranges[0] == Approx(0.5));   // straight right: the right wall
  CHECK(scan.ranges[30] == Approx(0.5));  // straight left: the left wall
  CHECK_FALSE(scan.Hit(15));              // straight ahead: between the posts, nothing near
  // Turned to face the left wall, the beam ahead meets it.
  robot.Place(1.0, 0.0, std::numbers::pi / 2);
  CHECK(robot.State().ranges.ranges[15] == Approx(0.5));
  // And the scan follows the robot as it drives: 0.2 m nearer after moving up.
  robot.Place(1.0, 0.2, std::numbers::pi / 2);
  robot.Update(1e-3);
  CHECK(robot.State().ranges.ranges[15] == Approx(0.3).margin(1e-3));
}

TEST_CASE("range noise is seeded, spread as configured, and spares beams that meet nothing") {
  const Track track(Corridor());
  const RangeSensorConfig config{
      .beams = 3, .fov_deg = 180.0, .max_range = 1.5, .noise_sd = 0.01, .seed = 7};
  std::mt19937_64 first(config.seed), second(config.seed);
  double sum = 0.0, sum2 = 0.0;
  constexpr int kScans = 2000;
  for (int i = 0; i < kScans; ++i) {
    const RangeScan a = ScanTrack(track, 1.0, 0.0, 0.0, config, first);
    const RangeScan b = ScanTrack(track, 1.0, 0.0, 0.0, config, second);
    REQUIRE(a.ranges == b.ranges);  // the same seed, the same readings
    CHECK(a.ranges[1] == 1.5f);     // straight ahead meets nothing: exact
    const double error = a.ranges[0] - 0.5;
    sum += error;
    sum2 += error * error;
  }
  const double mean = sum / kScans;
  CHECK(std::abs(mean) < 0.001);
  CHECK(std::sqrt(sum2 / kScans - mean * mean) == Approx(0.01).epsilon(0.1));
}

TEST_CASE("false and missing echoes come at their rates, seeded, without moving the noise") {
  const Track track(Corridor());
  const RangeSensorConfig config{
      .beams = 31, .fov_deg = 180.0, .max_range = 1.5, .noise_sd = 0.0, .seed = 7};
  const RangeFaults faults{.spurious = 0.1, .dropout = 0.2};
  std::mt19937_64 noise(1), echoes(2), again_noise(1), again_echoes(2), plain_noise(1);
  const RangeScan exact = ScanTrack(track, 1.0, 0.0, 0.0, config, plain_noise);
  int hits = 0, spurious = 0, dropped = 0, beams = 0;
  for (int i = 0; i < 400; ++i) {
    const RangeScan a = ScanTrack(track.walls(), track.round_obstacles(), 1.0, 0.0, 0.0, config,
                                  noise, faults, echoes);
    const RangeScan b = ScanTrack(track.walls(), track.round_obstacles(), 1.0, 0.0, 0.0, config,
                                  again_noise, faults, again_echoes);
    REQUIRE(a.ranges == b.ranges);  // one seed, one scan
    for (int k = 0; k < a.count; ++k) {
      ++beams;
      const float got = a.ranges[static_cast<size_t>(k)];
      const float want = exact.ranges[static_cast<size_t>(k)];
      if (exact.Hit(k)) ++hits;
      if (got == want) continue;
      if (exact.Hit(k) && got == 1.5f) {
        ++dropped;
      } else {
        ++spurious;
      }
    }
  }
  // A false echo on any beam; a missing one only on a beam that met something.
  CHECK(spurious == Approx(0.1 * beams).epsilon(0.15));
  CHECK(dropped == Approx(0.9 * 0.2 * hits).epsilon(0.15));
}

TEST_CASE("a robot without range sensors reports an empty scan") {
  const Track track(Corridor());
  VehicleConfig config;
  config.range_sensors.beams = 0;
  SimRobot robot(track, config);
  CHECK(robot.State().ranges.count == 0);
}
