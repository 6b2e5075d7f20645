#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/config/error.hpp"
#include "haptel/vehicles/sim_robot.hpp"
#include "haptel/vehicles/vehicle_node.hpp"
#include "haptel/video/camera_source.hpp"

using namespace haptel;
using namespace haptel::models;
using namespace haptel::vehicles;

namespace {
/// A straight corridor along x from 0 to 4 m, 1 m wide, one gate at 2 m.
TrackConfig Corridor() {
  TrackConfig t;
  t.name = "corridor";
  t.centerline = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  t.corridor_width = 1.0;
  t.post_radius = 0.04;
  t.gates = {{2.0, 0.6}};
  return t;
}
void Drive(SimRobot& r, MotorLevels levels, double seconds) {
  r.SetMotors(levels);
  for (int i = 0; i < static_cast<int>(seconds * 200); ++i) r.Update(1.0 / 200);
}
}  // namespace

TEST_CASE("full forward reaches the configured top speed in a straight line") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.right_gain = 1.0;
  SimRobot r(track, cfg);
  r.Place(0.2, -0.25, 0.0);  // off the centre, away from the gate posts
  Drive(r, {8, 8}, 2.0);
  const AdapterState s = r.State();
  CHECK(s.speed == Approx(cfg.drive.max_speed).epsilon(0.01));
  CHECK(s.y == Approx(-0.25).margin(1e-9));
  CHECK(s.x > 0.2 + 0.5);
  CHECK_FALSE(s.bumper_left);
}

TEST_CASE(
    "a late tick's whole time is driven (a starved vehicle thread): 0.3 s in one update goes as "
    "far as in 5-ms ticks") {
  const Track track(Corridor());
  VehicleConfig cfg;
  SimRobot ticked(track, cfg), late(track, cfg);
  for (SimRobot* r : {&ticked, &late}) {
    r->Place(0.2, -0.25, 0.0);
    Drive(*r, {8, 6}, 0.5);  // moving and turning
  }
  const AdapterState before = late.State();
  Drive(ticked, {8, 6}, 0.3);
  late.Update(0.3);
  const AdapterState a = ticked.State(), b = late.State();
  CHECK(std::hypot(b.x - a.x, b.y - a.y) < 0.002);  // the body stepped in 50-ms pieces
  CHECK(b.heading == Approx(a.heading).margin(0.01));
  // It moved for all 0.3 s (capped at 50 ms, a sixth of it).
  CHECK(std::hypot(b.x - before.x, b.y - before.y) > 0.3 * 0.5 * cfg.drive.max_speed);
}

TEST_CASE("uneven motor gains make equal levels curve toward the weaker side") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.right_gain = 0.9;
  SimRobot r(track, cfg);
  r.Place(0.3, 0.2, 0.0);
  Drive(r, {4, 4}, 2.0);
  CHECK(r.State().heading < 0.0);  // right tread slower: turns right (clockwise)
}

TEST_CASE("opposite levels turn in place") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.right_gain = 1.0;
  SimRobot r(track, cfg);
  r.Place(1.0, 0.0, 0.0);
  Drive(r, {-4, 4}, 1.0);
  const AdapterState s = r.State();
  CHECK(s.heading > 0.5);  // counter-clockwise
  CHECK(std::hypot(s.x - 1.0, s.y) < 1e-6);
}

TEST_CASE("the body cannot enter a wall, and a head-on contact closes both switches") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.right_gain = 1.0;  // no drift: a true head-on approach
  SimRobot r(track, cfg);
  // Face the outer wall (y = -0.5) head-on.
  r.Place(1.0, -0.2, -std::numbers::pi / 2);
  Drive(r, {8, 8}, 3.0);
  const AdapterState s = r.State();
  CHECK(s.y >= -0.5 + cfg.body.radius - 1e-9);
  CHECK(s.bumper_left);
  CHECK(s.bumper_right);
  CHECK(std::abs(s.speed) < 0.01);  // blocked
}

TEST_CASE("a contact on the front-left closes only the left switch") {
  const Track track(Corridor());
  VehicleConfig cfg;
  SimRobot r(track, cfg);
  // Heading along x with the left wall (y = +0.5) 45 degrees to the left.
  r.Place(1.0, 0.3, std::numbers::pi / 4);
  Drive(r, {8, 8}, 2.0);
  const AdapterState s = r.State();
  CHECK(s.bumper_left);
  CHECK_FALSE(s.bumper_right);
  CHECK(s.y <= 0.5 - cfg.body.radius + 1e-9);
}

TEST_CASE("reversing into a wall stops the robot but closes no front switch") {
  const Track track(Corridor());
  VehicleConfig cfg;
  SimRobot r(track, cfg);
  r.Place(1.0, -0.2, std::numbers::pi / 2);  // back to the outer wall
  Drive(r, {-8, -8}, 3.0);
  const AdapterState s = r.State();
  CHECK(s.y >= -0.5 + cfg.body.radius - 1e-9);
  CHECK_FALSE(s.bumper_left);
  CHECK_FALSE(s.bumper_right);
}

TEST_CASE("gate posts are solid") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.right_gain = 1.0;
  SimRobot r(track, cfg);
  const Gate& g = track.gates()[0];
  r.Place(g.left_post.x() - 0.5, g.left_post.y(), 0.0);  // straight at the left post
  Drive(r, {6, 6}, 4.0);
  const AdapterState s = r.State();
  const double distance = std::hypot(s.x - g.left_post.x(), s.y - g.left_post.y());
  CHECK(distance >= cfg.body.radius + track.config().post_radius - 1e-6);
  CHECK((s.bumper_left || s.bumper_right));
}

TEST_CASE("stopping the adapter brings the treads to rest") {
  const Track track(Corridor());
  VehicleConfig cfg;
  SimRobot r(track, cfg);
  r.Place(0.5, -0.25, 0.0);
  Drive(r, {8, 8}, 1.0);
  REQUIRE(r.State().speed > 0.2);
  r.Stop();
  Drive(r, {0, 0}, 1.0);
  CHECK(r.State().applied.left == 0);
  CHECK(std::abs(r.State().speed) < 1e-3);
}

TEST_CASE(
    "the sim robot and the vehicle node refuse a config VehicleConfig::ValidateOrThrow refuses") {
  const Track track(Corridor());
  VehicleConfig cfg;
  cfg.drive.track_width = 0.0;
  CHECK_THROWS_WITH(SimRobot(track, cfg),
                    Catch::Contains("drive.track_width: expected a number in [0.02, 5]"));
  CHECK_THROWS_AS(SimRobot(track, cfg), ConfigFieldError);
  // Before any DDS participant is made: the node's config is checked first.
  auto camera = video::MakeCameraSource(cfg.camera, &track, "test");
  CHECK_THROWS_WITH(
      RobotNode(cfg, std::move(camera), std::make_unique<SimRobot>(track, VehicleConfig{})),
      Catch::Contains("drive.track_width"));
}
