// The cockpit's physical controls: wheel and throttle end stops, the shake
// torque, the return-to-zero springs, the throttle lock, and a proxy hand
// that holds and turns the wheel.
#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <thread>

#include "alloc_counter.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/physics/world.hpp"
#include "test_env.hpp"

namespace {

using haptel::CockpitConfig;
using haptel::PhysicsConfig;
using haptel::haptics::HandSample;
using haptel::haptics::Side;
using haptel::physics::CockpitControlsBody;
using haptel::physics::ControlsActuation;
using haptel::physics::ControlsState;
using haptel::physics::PhysicsWorld;

CockpitConfig Cockpit() {
  return haptel::LoadCockpit(haptel::ShippedFile("config/interfaces/cockpit.yaml"));
}

struct Rig {
  PhysicsWorld world{PhysicsConfig{}};
  CockpitConfig cockpit = Cockpit();
  CockpitControlsBody controls{world, cockpit};
  double max_angle = cockpit.wheel_max_angle_deg * M_PI / 180.0;

  /// `steps` steps under `a`, with an optional push (N, along x) on the knob.
  ControlsState Run(const ControlsActuation& a, int steps, double knob_push = 0.0) {
    controls.Apply(a);
    for (int i = 0; i < steps; ++i) {
      if (knob_push != 0.0) controls.throttle_body().applyCentralForce(btVector3(knob_push, 0, 0));
      world.Step();
    }
    return controls.Read();
  }
};

ControlsActuation Torque(double t) {
  ControlsActuation a;
  a.wheel_torque = t;
  return a;
}

}  // namespace

TEST_CASE("cockpit controls: the wheel stops at its end stops under a steady torque",
          "[physics][cockpit]") {
  Rig rig;
  CHECK(rig.controls.Read().wheel_angle == Approx(0.0).margin(1e-9));
  ControlsState s = rig.Run(Torque(0.5), 2000);  // + = toward the left
  CHECK(s.wheel_angle == Approx(rig.max_angle).margin(0.02));
  CHECK_FALSE(s.wheel_held);
  s = rig.Run(Torque(-0.5), 3000);
  CHECK(s.wheel_angle == Approx(-rig.max_angle).margin(0.02));
  // The rim stays on its hub.
  const btVector3 hub = rig.controls.wheel_body().getWorldTransform().getOrigin();
  CHECK(hub.x() == Approx(rig.cockpit.wheel_hub[0]).margin(1e-3));
  CHECK(hub.y() == Approx(rig.cockpit.wheel_hub[1]).margin(1e-3));
  CHECK(hub.z() == Approx(rig.cockpit.wheel_hub[2]).margin(1e-3));
}

TEST_CASE("cockpit controls: a shake torque makes the wheel oscillate, then it settles",
          "[physics][cockpit]") {
  Rig rig;
  const auto& c = rig.cockpit;
  const double h = rig.world.config().step_s;
  const int shake_steps = static_cast<int>(c.shake_s / h);
  double lo = 1e9, hi = -1e9, previous = 0.0, previous_delta = 0.0;
  int reversals = 0;
  for (int i = 0; i < shake_steps; ++i) {
    const double angle =
        rig.Run(Torque(c.shake_torque * std::sin(2 * M_PI * c.shake_hz * i * h)), 1).wheel_angle;
    lo = std::min(lo, angle);
    hi = std::max(hi, angle);
    const double delta = angle - previous;
    if (delta * previous_delta < 0.0) ++reversals;
    if (delta != 0.0) previous_delta = delta;
    previous = angle;
  }
  INFO("angle range " << lo << " .. " << hi << ", " << reversals << " reversals");
  CHECK(hi - lo > 0.005);
  CHECK(reversals >= 2 * static_cast<int>(c.shake_s * c.shake_hz) - 2);
  rig.Run(Torque(0.0), 3000);
  const double settled = rig.controls.Read().wheel_angle;
  CHECK(std::abs(rig.controls.wheel_body().getAngularVelocity().x()) < 1e-3);
  CHECK(rig.Run(Torque(0.0), 500).wheel_angle == Approx(settled).margin(1e-3));
  CHECK(std::abs(settled) < rig.max_angle);
}

TEST_CASE("cockpit controls: the assisted springs return the released wheel and lever to zero",
          "[physics][cockpit]") {
  Rig rig;
  const auto& c = rig.cockpit;
  ControlsActuation a;
  a.wheel_torque = 0.3;
  a.throttle_spring = c.throttle_return_stiffness;
  a.throttle_target = 0.04;
  ControlsState s = rig.Run(a, 3000);  // turned and pushed away from zero
  CHECK(s.wheel_angle > 1.0);
  CHECK(s.throttle == Approx(0.04).margin(0.002));

  a = {};
  a.wheel_spring = c.wheel_return_stiffness;
  a.throttle_spring = c.throttle_return_stiffness;
  s = rig.Run(a, 5000);
  CHECK(s.wheel_angle == Approx(0.0).margin(0.01));
  CHECK(s.throttle == Approx(0.0).margin(0.001));
}

TEST_CASE("cockpit controls: the throttle stops at its end stops", "[physics][cockpit]") {
  Rig rig;
  const double travel = rig.cockpit.throttle_travel;
  ControlsState s = rig.Run({}, 1000, 5.0);
  CHECK(s.throttle == Approx(travel).margin(0.002));
  s = rig.Run({}, 1000, -5.0);
  CHECK(s.throttle == Approx(-travel).margin(0.002));
  // Only along x: the knob stays on its rail.
  const btVector3 p = rig.controls.throttle_body().getWorldTransform().getOrigin();
  CHECK(p.y() == Approx(rig.cockpit.throttle_centre[1]).margin(1e-3));
  CHECK(p.z() == Approx(rig.cockpit.throttle_centre[2]).margin(1e-3));
}

TEST_CASE("cockpit controls: a locked lever holds at the target against a push; release frees it",
          "[physics][cockpit]") {
  Rig rig;
  ControlsActuation a;
  a.throttle_locked = true;
  a.throttle_target = 0.0;
  ControlsState s = rig.Run(a, 1000, 20.0);
  CHECK(s.throttle == Approx(0.0).margin(0.001));
  s = rig.Run(a, 1000, -20.0);
  CHECK(s.throttle == Approx(0.0).margin(0.001));
  a.throttle_locked = false;
  s = rig.Run(a, 1000, 5.0);
  CHECK(s.throttle == Approx(rig.cockpit.throttle_travel).margin(0.002));
  // Locking again brings it to the target and holds it there.
  a.throttle_locked = true;
  s = rig.Run(a, 1000, 5.0);
  CHECK(s.throttle == Approx(0.0).margin(0.001));
}

/// Shared control's guidance (cockpit-shared): a plane at `throttle` (m) and
/// `wheel_angle` (rad), normal (lever, rim), 150 N/m, at most 3 N.
ControlsActuation Guiding(double throttle, double wheel_angle, double normal_throttle,
                          double normal_rim) {
  ControlsActuation a;
  a.guidance_active = true;
  a.guidance_throttle = throttle;
  a.guidance_wheel_angle = wheel_angle;
  a.guidance_normal_throttle = normal_throttle;
  a.guidance_normal_rim = normal_rim;
  a.guidance_stiffness = 150.0;
  a.guidance_max_force = 3.0;
  return a;
}

TEST_CASE(
    "cockpit controls: shared control's guidance pushes the lever back to its plane, and a hand "
    "pushes through",
    "[physics][cockpit]") {
  Rig rig;
  const ControlsActuation a =
      Guiding(0.02, 0.0, 1.0, 0.0);  // commands beyond 2 cm forward lead into danger
  // Pushed forward by 1 N, the lever rests where the spring answers it: 1/150 m past the plane.
  ControlsState s = rig.Run(a, 3000, 1.0);
  CHECK(s.throttle == Approx(0.02 + 1.0 / 150.0).margin(0.001));
  CHECK(rig.controls.guidance_force() == Approx(1.0).margin(0.05));
  // Pushed by more than the bound, it goes through to its end stop: the guidance never locks.
  s = rig.Run(a, 3000, 5.0);
  CHECK(s.throttle == Approx(rig.cockpit.throttle_travel).margin(0.002));
  CHECK(rig.controls.guidance_force() == Approx(3.0));  // saturated, however deep
  // Let go, it comes back to the plane and no further: a one-sided spring.
  s = rig.Run(a, 4000);
  CHECK(s.throttle == Approx(0.02).margin(0.002));
  CHECK(s.throttle > 0.017);
  // Off: nothing pushes.
  s = rig.Run({}, 1000, 1.0);
  CHECK(s.throttle == Approx(rig.cockpit.throttle_travel).margin(0.002));
  CHECK(rig.controls.guidance_force() == 0.0);
}

TEST_CASE(
    "cockpit controls: shared control's guidance turns the wheel back from a steer to the left",
    "[physics][cockpit]") {
  Rig rig;
  const double r = rig.cockpit.wheel_radius;
  const ControlsActuation push_left = [] {
    ControlsActuation a =
        Guiding(0.0, 0.1, 0.0, 1.0);  // steering left of 0.1 rad leads into danger
    return a;
  }();
  // A steady 0.2 N·m to the left: it rests where the rim's spring answers it,
  // (0.2 / r) N = 150 N/m × the rim's arc past the plane.
  ControlsActuation a = push_left;
  a.wheel_torque = 0.2;
  ControlsState s = rig.Run(a, 4000);
  CHECK(s.wheel_angle == Approx(0.1 + (0.2 / r) / 150.0 / r).margin(0.01));
  // 0.5 N·m is more than the bound's 3 N × r = 0.36 N·m: through, to the end stop.
  a.wheel_torque = 0.5;
  s = rig.Run(a, 4000);
  CHECK(s.wheel_angle == Approx(rig.max_angle).margin(0.02));
  CHECK(rig.controls.guidance_force() == Approx(3.0));
  // A steer to the right is safe: left alone.
  a.wheel_torque = -0.2;
  s = rig.Run(a, 6000);
  CHECK(s.wheel_angle == Approx(-rig.max_angle).margin(0.02));
  CHECK(rig.controls.guidance_force() == 0.0);
  // A guidance that is not finite pushes nothing (and breaks nothing).
  a = push_left;
  a.guidance_throttle = std::nan("");
  a.wheel_torque = 0.2;
  s = rig.Run(a, 6000);
  CHECK(s.wheel_angle == Approx(rig.max_angle).margin(0.02));
  CHECK(rig.controls.guidance_force() == 0.0);
}

TEST_CASE("cockpit controls: a proxy hand closed on the rim holds it and turns the wheel",
          "[physics][cockpit]") {
  Rig rig;
  rig.world.AddHand(Side::kRight);
  const auto& hub = rig.cockpit.wheel_hub;
  const double r = rig.cockpit.wheel_radius;
  // Palm down over the top of the rim, fingers forward (+x) over it, the rim
  // under the metacarpals; the rim's tangent there (y) is the fingers'
  // flexion axis, so closing the fingers wraps them around it.
  const double rim = 0.012;  // ControlsBodyConfig{}.rim_radius
  const double finger_r = rig.world.config().hand.phalanx_radius;
  const std::array<double, 3> wrist{hub[0] - 0.115, hub[1], hub[2] + r + rim + finger_r};

  /// The tracked hand turned by `angle` about the hub (about −x: + = left),
  /// `down` m into the rim, fingers closed by `close` (0..1).
  auto sample = [&](double angle, double down, double close) {
    HandSample s;
    s.valid = true;
    const double c = std::cos(angle), sn = std::sin(angle);
    const double y = wrist[1] - hub[1], z = wrist[2] - down - hub[2];
    // Rotation about −x by angle: (y, z) → (c·y + s·z, −s·y + c·z).
    s.position = {wrist[0], hub[1] + c * y + sn * z, hub[2] - sn * y + c * z};
    s.orientation = {std::cos(0.5 * angle), -std::sin(0.5 * angle), 0, 0};
    for (int f = 0; f < 4; ++f) {
      s.finger_angles[4 + 3 * f] = 0.2 * close;      // MCP
      s.finger_angles[4 + 3 * f + 1] = 1.6 * close;  // PIP
      s.finger_angles[4 + 3 * f + 2] = 1.4 * close;  // DIP
    }
    return s;
  };
  auto run = [&](int steps, auto&& tracked) {
    for (int i = 0; i < steps; ++i) {
      rig.world.hand(Side::kRight)->SetTracked(tracked(i));
      rig.world.Step();
    }
    return rig.controls.Read();
  };

  ControlsState s = run(300, [&](int) { return sample(0.0, -0.03, 0.0); });  // above, open
  CHECK_FALSE(s.wheel_held);
  s = run(500, [&](int i) { return sample(0.0, -0.03 + 0.035 * std::min(1.0, i / 300.0), 0.0); });
  s = run(500, [&](int i) { return sample(0.0, 0.005, std::min(1.0, i / 300.0)); });  // close
  INFO("grasped: contacts " << s.wheel_contacts << ", angle " << s.wheel_angle);
  CHECK(s.wheel_held);
  CHECK(s.wheel_contacts >= 4);
  CHECK(std::abs(s.wheel_angle) < 0.05);
  CHECK_FALSE(s.throttle_held);

  for (double target : {0.6, -0.6}) {
    const double from = s.wheel_angle;
    s = run(1000, [&](int i) { return sample(from + (target - from) * i / 1000.0, -0.003, 1.0); });
    s = run(500, [&](int) { return sample(target, -0.003, 1.0); });
    INFO("turned to " << target << ": wheel " << s.wheel_angle << ", contacts "
                      << s.wheel_contacts);
    CHECK(s.wheel_angle == Approx(target).margin(0.1));
    CHECK(s.wheel_held);
  }

  // Opened, the same hand no longer carries the wheel: the closed fingers,
  // not the palm's friction, turned it (the palm was not pressing).
  s = run(300, [&](int i) { return sample(-0.6, -0.003, 1.0 - std::min(1.0, i / 200.0)); });
  const double released_at = s.wheel_angle;
  s = run(1000, [&](int i) { return sample(-0.6 + 0.6 * i / 1000.0, -0.003, 0.0); });
  CHECK(s.wheel_angle == Approx(released_at).margin(0.1));
  // Lifted off: released.
  s = run(500, [&](int i) { return sample(0.0, -0.003 - 0.05 * std::min(1.0, i / 300.0), 0.0); });
  CHECK_FALSE(s.wheel_held);
  CHECK(rig.world.Counters().hand_resets == 0);
  CHECK(rig.controls.resets() == 0);
}

TEST_CASE("cockpit controls: a palm pushes the lever, not while it is locked",
          "[physics][cockpit]") {
  Rig rig;
  rig.world.AddHand(Side::kRight);
  const auto& centre = rig.cockpit.throttle_centre;
  const auto& hc = rig.world.config().hand;
  // Palm facing +x (the hand turned −90° about y, fingers up), behind the knob.
  const double knob_back = centre[0] - haptel::physics::ControlsBodyConfig().knob_half_extents[0];
  const double x0 = knob_back - hc.palm_half_extents[2] - 0.02;  // 2 cm behind
  auto sample = [&](double x) {
    HandSample s;
    s.valid = true;
    s.position = {x, centre[1], centre[2] - hc.palm_half_extents[0]};
    s.orientation = {std::cos(-M_PI / 4), 0, std::sin(-M_PI / 4), 0};
    return s;
  };
  auto run = [&](const ControlsActuation& a, int steps, double from, double to) {
    rig.controls.Apply(a);
    for (int i = 0; i < steps; ++i) {
      rig.world.hand(Side::kRight)->SetTracked(sample(from + (to - from) * i / steps));
      rig.world.Step();
    }
    return rig.controls.Read();
  };
  ControlsActuation locked;
  locked.throttle_locked = true;
  ControlsState s = run(locked, 300, x0, x0);
  CHECK_FALSE(s.throttle_held);
  s = run(locked, 1000, x0, x0 + 0.04);  // 2 cm into the locked knob: ≈60 N
  s = run(locked, 300, x0 + 0.04, x0 + 0.04);
  CHECK(s.throttle_held);
  CHECK(s.throttle == Approx(0.0).margin(0.002));
  // Unlocked, with the assisted spring (a free knob would be thrown to its
  // stop): the palm holds it 2 cm forward against the spring.
  ControlsActuation sprung;
  sprung.throttle_spring = rig.cockpit.throttle_return_stiffness;
  s = run(sprung, 1000, x0 + 0.04, x0 + 0.04);
  CHECK(s.throttle_held);
  CHECK(s.throttle == Approx(0.02).margin(0.005));
  CHECK_FALSE(s.wheel_held);
}

TEST_CASE(
    "cockpit controls: the link trades state and actuation across threads' seqlocks, allocating "
    "nothing",
    "[physics][cockpit]") {
  Rig rig;
  rig.world.AddHand(Side::kRight);
  haptel::physics::ControlsLink link(rig.world, rig.controls);
  rig.controls.Read();  // gathers the hands' bodies once, as the session does before Start
  CHECK(link.State().wheel_angle == 0.0);
  // An actuation set from another thread acts from the next step on: a
  // steady torque turns the wheel to its stop, and the state says so.
  haptel::test::Thread interface_thread("interface", [&] { link.SetActuation(Torque(0.2)); });
  interface_thread.Join();
  for (int i = 0; i < 1500; ++i) rig.world.Step();
  CHECK(link.State().wheel_angle == Approx(rig.max_angle).margin(0.02));
  // The hooks, as the physics thread runs them around each step, allocate nothing.
  const uint64_t before = haptel::test::ThreadAllocations();
  for (int i = 0; i < 1000; ++i) {
    link.BeforeStep();
    link.AfterStep();
  }
  CHECK(haptel::test::ThreadAllocations() == before);
}

TEST_CASE("cockpit controls: refuse a cockpit or body config ValidateOrThrow refuses",
          "[physics][cockpit]") {
  PhysicsWorld world{PhysicsConfig{}};
  CockpitConfig cockpit = Cockpit();
  cockpit.wheel_max_angle_deg = 200.0;  // the hinge turns less than half a turn each way
  CHECK_THAT(haptel::test::WhatOf<haptel::ConfigFieldError>(
                 [&] { CockpitControlsBody controls(world, cockpit); }),
             Catch::Contains("wheel.max_angle_deg"));
  haptel::physics::ControlsBodyConfig bodies;
  bodies.rim_segments = 3;
  CHECK_THAT(haptel::test::WhatOf<haptel::ConfigFieldError>(
                 [&] { CockpitControlsBody controls(world, Cockpit(), bodies); }),
             Catch::Contains("rim_segments: expected a whole number in [6, 1000]"));
  bodies = {};
  bodies.material.restitution = 2.0;
  CHECK_THAT(haptel::test::WhatOf<haptel::ConfigFieldError>(
                 [&] { CockpitControlsBody controls(world, Cockpit(), bodies); }),
             Catch::Contains("material.restitution"));
}

TEST_CASE("cockpit controls: ControlsBodyConfig validates its defaults and names a bad key",
          "[physics][cockpit]") {
  using haptel::physics::ControlsBodyConfig;
  CHECK_NOTHROW(ControlsBodyConfig{}.ValidateOrThrow());
  ControlsBodyConfig c;
  c.wheel_mass = 0.0;
  CHECK_THAT(haptel::test::WhatOf<haptel::ConfigFieldError>([&] { c.ValidateOrThrow(); }),
             Catch::Contains("wheel_mass: expected a finite number > 0"));
  c = {};
  c.knob_half_extents[1] = std::nan("");
  CHECK_THAT(haptel::test::WhatOf<haptel::ConfigFieldError>([&] { c.ValidateOrThrow(); }),
             Catch::Contains("knob_half_extents"));
}
