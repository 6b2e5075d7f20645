// The simulated blimp's contacts with the world: resting on the ground at
// the start, a drop without its helium's lift, a fall at 10 m/s, a flight
// into a wall; the command mapping; and the airship's steady-wind physics
// the pilot relies on (the hull feels only its motion through the air).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "alloc_counter.hpp"
#include "haptel/config/blimp_course.hpp"
#include "haptel/config/error.hpp"
#include "haptel/models/airship_trials.hpp"
#include "haptel/models/sim_blimp.hpp"

using namespace haptel;
using namespace haptel::models;

namespace {

/// A start at the origin facing +x (east), a building "wall" whose near
/// face is 20 m ahead (x 20..40, y -20..20, 20 m tall), a gate and the
/// landing well away.
BlimpCourseConfig WallCourse() {
  BlimpCourseConfig c;
  c.name = "wall";
  c.start.position = {0.0, 0.0};
  c.start.heading_deg = 0.0;
  BlimpGateSpec g;
  g.name = "g";
  g.centre = {0.0, 100.0, 6.0};
  g.width = 10.0;
  g.height = 8.0;
  c.gates.push_back(g);
  BlimpBuildingSpec b;
  b.name = "wall";
  b.centre = {30.0, 0.0};
  b.size = {20.0, 40.0};
  b.height = 20.0;
  c.buildings.push_back(b);
  c.landing.centre = {-50.0, 0.0};
  c.landing.radius = 8.0;
  return c;
}

/// The lowest point of any contact feature (world z, m): below 0 is in the ground.
double LowestPoint(const SimBlimp& sim) {
  const AirshipState& s = sim.airship().state();
  double lowest = 1e9;
  for (const ContactSphere& sphere : sim.contact_model().spheres()) {
    lowest = std::min(lowest, (s.position + s.attitude * sphere.centre_body).z() - sphere.radius);
  }
  return lowest;
}

/// As heavy as without its helium's lift: the displaced air's mass added
/// (the weight then exceeds the buoyancy by the buoyancy itself).
AirshipConfig WithoutLift() {
  AirshipConfig c;
  c.payload_mass += c.air_density * c.volume;
  return c;
}

}  // namespace

TEST_CASE("the simulated blimp rests on its gondola at the course's start") {
  SimBlimp sim(AirshipConfig{}, WallCourse());
  const Eigen::Vector3d start = sim.position();
  CHECK(start.x() == Approx(0.0));
  CHECK(start.z() == Approx(sim.contact_model().lowest_below_cg()).margin(1e-3));
  CHECK(sim.on_ground());
  CHECK(sim.in_contact());
  CHECK(sim.contacts() == 0);  // resting at the start is no contact onset
  double drift = 0.0;
  for (int i = 0; i < 6000; ++i) {  // 30 s, motors off
    sim.Step(0.005, BlimpCommand{});
    drift = std::max(drift, (sim.position() - start).norm());
  }
  CHECK(sim.airship().Finite());
  CHECK(drift < 0.03);
  CHECK(sim.on_ground());
  CHECK(sim.contacts() == 0);
  CHECK(std::abs(sim.yaw()) < 1e-3);

  // The shipped course's heading is taken too.
  BlimpCourseConfig turned = WallCourse();
  turned.start.heading_deg = 90.0;
  CHECK(SimBlimp(AirshipConfig{}, turned).yaw() == Approx(M_PI / 2));
}

TEST_CASE("dropped from 5 m without its helium's lift the blimp lands without tunnelling") {
  SimBlimp sim(WithoutLift(), WallCourse());
  AirshipState s = sim.airship().state();
  s.position.z() = 5.0;
  sim.airship().set_state(s);
  double lowest = 1e9, first_impact = -1.0;
  for (int i = 0; i < 2000; ++i) {  // 10 s
    sim.Step(0.005, BlimpCommand{});
    lowest = std::min(lowest, LowestPoint(sim));
    if (first_impact < 0 && sim.contacts() > 0) first_impact = sim.last_impact_speed();
  }
  REQUIRE(sim.airship().Finite());
  CHECK(sim.contacts() >= 1);  // (and bounces: each a new onset, slower)
  CHECK(sim.last_obstacle() == 0);
  CHECK(first_impact > 3.0);  // fell about 4 m: a crash on any course
  CHECK(sim.last_impact_speed() <= first_impact);
  CHECK(lowest > -0.3);  // pressed into the ground a little, never through it
  CHECK(sim.on_ground());
  CHECK(sim.ground_velocity().norm() < 0.05);
  CHECK(LowestPoint(sim) > -0.05);  // at rest on the ground: sunk in by its weight only
}

TEST_CASE("falling at 10 m/s, pitched and rolled, the blimp stays finite and above the ground") {
  for (const double pitch : {0.0, 0.35}) {
    SimBlimp sim(WithoutLift(), WallCourse());
    AirshipState s = sim.airship().state();
    s.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(0.5 * pitch, Eigen::Vector3d::UnitX()));
    s.velocity = s.attitude.conjugate() * Eigen::Vector3d(0.0, 0.0, -10.0);  // body frame
    sim.airship().set_state(s);
    s.position.z() += 0.3 - LowestPoint(sim);  // 0.3 m to go, at 10 m/s
    sim.airship().set_state(s);
    double lowest = 1e9, first_impact = -1.0;
    bool finite = true;
    for (int i = 0; i < 2000; ++i) {
      sim.Step(0.005, BlimpCommand{});
      finite = finite && sim.airship().Finite();
      lowest = std::min(lowest, LowestPoint(sim));
      if (first_impact < 0 && sim.contacts() > 0) first_impact = sim.last_impact_speed();
    }
    INFO("pitch " << pitch);
    CHECK(finite);
    CHECK(first_impact == Approx(10.0).epsilon(0.1));
    CHECK(lowest > -0.8);  // the hull is 2.2 m across: sunk in, not through
    CHECK(sim.position().z() > 0.0);
    CHECK(LowestPoint(sim) > -0.05);
    CHECK(sim.ground_velocity().norm() < 0.1);
  }
}

TEST_CASE("flown into a building at 4 m/s the blimp stops at the wall and reports the impact") {
  const AirshipConfig neutral = NeutrallyBuoyant(AirshipConfig{});
  SimBlimp sim(neutral, WallCourse());
  // Cruising at 4 m/s, 6 m up, 10 m before the wall: thrust for the drag.
  const double drag = 0.5 * neutral.air_density * neutral.axial_drag_coefficient *
                      std::pow(neutral.volume, 2.0 / 3.0);
  AirshipState s = sim.airship().state();
  s.position = {10.0, 0.0, 6.0};
  s.velocity = {4.0, 0.0, 0.0};
  s.thrust = drag * 16.0;
  sim.airship().set_state(s);
  BlimpCommand cruise;
  cruise.power = s.thrust / neutral.max_thrust;
  double nose = 0.0, first_impact = -1.0;
  for (int i = 0; i < 2000; ++i) {  // 10 s
    sim.Step(0.005, cruise);
    if (first_impact < 0 && sim.contacts() > 0) first_impact = sim.last_impact_speed();
    const AirshipState& now = sim.airship().state();
    for (const ContactSphere& sphere : sim.contact_model().spheres()) {
      nose = std::max(nose, (now.position + now.attitude * sphere.centre_body).x() + sphere.radius);
    }
  }
  REQUIRE(sim.airship().Finite());
  CHECK(sim.contacts() >= 1);       // the first, then slower bounces against it
  CHECK(sim.last_obstacle() == 1);  // building 0
  CHECK(first_impact == Approx(4.0).epsilon(0.2));
  CHECK(sim.last_impact_speed() < first_impact);
  CHECK(nose < 20.5);                                // into the wall by less than half a metre
  CHECK(std::abs(sim.ground_velocity().x()) < 0.3);  // stopped at it (the motors still push)
  CHECK(sim.position().x() < 20.0);
  CHECK(sim.position().x() > 14.0);
}

TEST_CASE("Step maps the command to the actuators, clamps it and keeps the camera's angles") {
  SimBlimp sim(AirshipConfig{}, WallCourse());
  BlimpCommand c;
  c.power = 2.0;
  c.helix = 1.0;
  c.camera_pan = 3.0;
  c.camera_tilt = -0.3;
  c.rudder = std::nan("");
  sim.Step(3.0, c);
  CHECK(sim.applied().power == 1.0);
  CHECK(sim.applied().rudder == 0.0);
  CHECK(sim.camera_pan() == Approx(kBlimpCameraPanMax));
  CHECK(sim.camera_tilt() == Approx(-0.3));
  CHECK(sim.time_s() == Approx(3.0));
  // Full power, the helix plane up: it lifts off.
  CHECK(sim.position().z() > sim.contact_model().lowest_below_cg() + 0.5);
  CHECK_FALSE(sim.on_ground());
  CHECK(sim.airspeed() > 0.1);
}

TEST_CASE("stepping the simulated blimp allocates nothing") {
  SimBlimp sim(AirshipConfig{}, WallCourse());
  BlimpCommand c;
  c.power = 0.5;
  sim.Step(0.05, c);
  const uint64_t before = haptel::test::ThreadAllocations();
  for (int i = 0; i < 200; ++i) sim.Step(0.05, c);
  CHECK(haptel::test::ThreadAllocations() == before);
}

TEST_CASE("bad contact parameters are refused by name") {
  BlimpContactConfig bad;
  bad.stiffness = 0.0;
  try {
    SimBlimp sim(AirshipConfig{}, WallCourse(), bad);
    FAIL("no error");
  } catch (const ConfigFieldError& e) {
    CHECK(e.key == "stiffness");
  }
}

TEST_CASE("in a steady wind the airship drifts with the air and does not turn") {
  // Galilean invariance: moving with a uniform wind, the hull is at rest in
  // the air, so no drag, no fin force and no Munk moment act on it, however
  // it lies across the wind.
  AirshipConfig c = NeutrallyBuoyant(AirshipConfig{});
  c.wind.mean = {2.0, 1.0, 0.0};
  Airship ship(c);
  AirshipState s;
  s.position = {0.0, 0.0, 50.0};
  s.attitude = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  s.velocity = s.attitude.conjugate() * Eigen::Vector3d(2.0, 1.0, 0.0);
  ship.set_state(s);
  ship.Advance(60.0, {});
  CHECK(std::abs(ship.YawPitchRoll().x() - 0.7) < 1e-6);
  CHECK(ship.Airspeed().norm() < 1e-6);
  CHECK((ship.state().position - Eigen::Vector3d(120.0, 60.0, 50.0)).norm() < 1e-4);
}
