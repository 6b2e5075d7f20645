// Every config struct's ValidateOrThrow: a default-constructed struct is valid
// (but for the two that are data, a track and a gravity grid), and a struct
// built in code with one bad value is refused with a ConfigFieldError naming
// the key (as the file spells it) and what was expected. The loaders turn the
// same error into a ConfigError at the key's line; the last cases check that
// translation where the key is not in the file.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include "haptel/config/calibration.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/config/gamepad.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/gravity_grid.hpp"
#include "haptel/config/keyboard.hpp"
#include "haptel/config/link.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "test_env.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using haptel::ConfigError;
using haptel::ConfigFieldError;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

/// The ConfigFieldError `config.ValidateOrThrow()` throws ("(valid)" when none).
template <typename Config>
ConfigFieldError ErrorOf(const Config& config) {
  try {
    config.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    return e;
  }
  return ConfigFieldError("(valid)", "");
}

template <typename Config>
std::string KeyOf(const Config& config) {
  return ErrorOf(config).key;
}

fs::path Write(const std::string& name, const std::string& text) {
  static const fs::path dir = haptel::test::ScratchDir("test_validate");
  return haptel::test::WriteFile(dir / name, text);
}

template <typename F>
std::string LoadErrorOf(F&& f) {
  return haptel::test::WhatOf<ConfigError>(std::forward<F>(f));
}

/// A valid 4 m x 3 m loop with one gate.
haptel::TrackConfig Loop() {
  haptel::TrackConfig t;
  t.name = "loop";
  t.centerline = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  t.corridor_width = 1.0;
  t.gates = {{2.0, 0.6}};
  return t;
}

/// A valid 2x2x2 grid.
haptel::GravityGridData Grid() {
  haptel::GravityGridData g;
  g.min = {0, 0, 0};
  g.max = {1, 1, 1};
  g.counts = {2, 2, 2};
  g.force_z.assign(8, 1.0);
  return g;
}

}  // namespace

TEST_CASE("ConfigFieldError: one exception type, key and expectation in what()",
          "[config][validate]") {
  const ConfigFieldError e("phalanx_radius", "a number in [0.001, 0.05]");
  CHECK(std::string(e.what()) == "phalanx_radius: expected a number in [0.001, 0.05]");
  const std::invalid_argument& base = e;  // constructors' callers may catch the standard type
  CHECK_THAT(base.what(), Contains("phalanx_radius"));

  const ConfigFieldError nested = ConfigFieldError("x", "y", {"z"}).Within("hand").Within("a[1]");
  CHECK(nested.key == "a[1].hand.x");
  CHECK(nested.related == std::vector<std::string>{"a[1].hand.z"});
  CHECK(ConfigFieldError("[2]", "y").Within("gains").key == "gains[2]");
  CHECK(std::string(ConfigFieldError("force_z", "8 forces", {}, "7").what()) ==
        "force_z: expected 8 forces, got 7");
}

TEST_CASE("PhysicsConfig, ProxyHandConfig, PhysicsMaterial", "[config][validate]") {
  CHECK_NOTHROW(haptel::PhysicsMaterial{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::ProxyHandConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::PhysicsConfig{}.ValidateOrThrow());

  haptel::PhysicsConfig c;
  c.hand.phalanx_radius = 0.2;  // a range
  const ConfigFieldError e = ErrorOf(c);
  CHECK(e.key == "hand.phalanx_radius");
  CHECK(e.expected == "a number in [0.001, 0.05]");

  c = {};
  c.step_s = kNaN;  // not finite
  CHECK(KeyOf(c) == "step_s");
  c = {};
  c.gravity[2] = -kInf;
  CHECK(KeyOf(c) == "gravity");
  c = {};
  c.solver_iterations = 0;
  CHECK(KeyOf(c) == "solver_iterations");

  c = {};
  c.hand.phalanx_radius = 0.012;  // in range, but 2 * 0.012 > the distal phalanx (0.022)
  const ConfigFieldError rule = ErrorOf(c);
  CHECK(rule.key == "hand.phalanx_length");
  CHECK_THAT(rule.expected, Contains("2 * phalanx_radius"));
  CHECK(rule.related == std::vector<std::string>{"hand.phalanx_radius"});

  c = {};
  c.hand.material.rolling_friction = 0.0;  // the default spinning friction then does nothing
  CHECK(KeyOf(c) == "hand.material.spinning_friction");
  haptel::PhysicsMaterial m;
  m.friction = kNaN;
  CHECK(KeyOf(m) == "friction");
}

TEST_CASE("PhysicsConfig: a reference run may step finer than a thread, nothing else may",
          "[config][validate]") {
  // The work-precision benchmark's ground truth steps at 0.025 ms.
  haptel::PhysicsConfig c;
  c.step_s = 2.5e-5;
  const ConfigFieldError thread = ErrorOf(c);
  CHECK(thread.key == "step_s");
  CHECK(thread.expected == "a number in [0.0001, 0.01]");
  c.reference = true;
  CHECK_NOTHROW(c.ValidateOrThrow());
  // Still bounded, and still bound by every other rule.
  c.step_s = 0.0;
  CHECK(KeyOf(c) == "step_s");
  c.step_s = 0.02;
  CHECK(KeyOf(c) == "step_s");
  c.step_s = 2.5e-5;
  c.solver_iterations = 0;
  CHECK(KeyOf(c) == "solver_iterations");

  // A file cannot ask for it: `reference` is no key of physics.yaml.
  const fs::path file = Write("reference.yaml", "step_s: 0.001\nreference: true\n");
  CHECK_THAT(LoadErrorOf([&] { haptel::LoadPhysics(file); }), Contains("reference"));
  const fs::path fine = Write("fine.yaml", "step_s: 0.000025\n");
  CHECK_THAT(LoadErrorOf([&] { haptel::LoadPhysics(fine); }), Contains("step_s"));
}

TEST_CASE("CockpitConfig", "[config][validate]") {
  CHECK_NOTHROW(haptel::CockpitConfig{}.ValidateOrThrow());
  haptel::CockpitConfig c;
  c.wheel_radius = 0.01;
  CHECK(KeyOf(c) == "wheel.radius");
  c = {};
  c.throttle_centre[1] = kNaN;
  CHECK(KeyOf(c) == "throttle.centre");
  c = {};
  c.wheel_max_angle_deg = 180.0;  // the hinge turns less than half a turn each way
  CHECK(KeyOf(c) == "wheel.max_angle_deg");
  c = {};
  c.wheel_full_turn_deg = 150.0;  // past the end stops (135)
  const ConfigFieldError e = ErrorOf(c);
  CHECK(e.key == "wheel.full_turn_deg");
  CHECK(e.expected == "full_turn_deg <= max_angle_deg");
  c = {};
  c.name.clear();
  CHECK(KeyOf(c) == "name");
}

TEST_CASE("GestureConfig, KeyboardConfig, GamepadConfig", "[config][validate]") {
  CHECK_NOTHROW(haptel::GestureConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::KeyboardConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::GamepadConfig{}.ValidateOrThrow());

  haptel::GestureConfig g;
  g.dead_zone = 0.5;
  CHECK(KeyOf(g) == "dead_zone");
  g = {};
  g.wall_stiffness = kInf;
  CHECK(KeyOf(g) == "wall_stiffness");
  g = {};
  g.name = "near";  // in code the name is a label: any will do
  CHECK_NOTHROW(g.ValidateOrThrow());

  haptel::KeyboardConfig k;
  k.repeat_s = 0.0;
  CHECK(KeyOf(k) == "repeat_s");
  k = {};
  k.command_rate_hz = kNaN;
  CHECK(KeyOf(k) == "command_rate_hz");

  haptel::GamepadConfig p;
  p.trigger_dead_zone = 1.0;
  CHECK(KeyOf(p) == "trigger_dead_zone");
  p = {};
  p.deadman = static_cast<haptel::GamepadDeadman>(42);
  CHECK(KeyOf(p) == "deadman");
}

TEST_CASE("TrackConfig", "[config][validate]") {
  // A default TrackConfig has no name, centre line or gate: it is data to fill
  // in, not a track.
  haptel::TrackConfig t;
  CHECK(KeyOf(t) == "name");
  t.name = "loop";
  CHECK(KeyOf(t) == "centerline");
  CHECK_NOTHROW(Loop().ValidateOrThrow());

  t = Loop();
  t.centerline.resize(2);
  CHECK(KeyOf(t) == "centerline");
  t = Loop();
  t.corridor_width = 50.0;
  CHECK(KeyOf(t) == "corridor_width");
  t = Loop();
  t.centerline[2] = {kNaN, 3.0};
  CHECK(KeyOf(t) == "centerline[2]");
  t = Loop();
  t.gates.push_back({1.0, 0.6});  // behind the first gate
  CHECK(KeyOf(t) == "gates[1].along");
  t = Loop();
  t.gates[0].width = 0.95;  // with 2 * 0.04 of post, wider than the 1 m corridor
  const ConfigFieldError wide = ErrorOf(t);
  CHECK(wide.key == "gates[0].width");
  CHECK_THAT(wide.expected, Contains("posts inside the corridor"));
  t = Loop();
  t.gates.clear();
  CHECK(KeyOf(t) == "gates");
  t = Loop();
  t.corridor_width = 3.5;  // the lanes 3 m apart overlap
  CHECK(KeyOf(t) == "corridor_width");
  t = Loop();
  t.obstacles.push_back({{1.0, 1.0}, 0.0});
  CHECK(KeyOf(t) == "obstacles[0].radius");
}

TEST_CASE("VehicleConfig and its parts, LinkConfig", "[config][validate]") {
  CHECK_NOTHROW(haptel::TreadDriveConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::BodyConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::CameraConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::LinkConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::VehicleConfig{}.ValidateOrThrow());

  haptel::VehicleConfig v;
  v.drive.speed_levels = 0;
  CHECK(KeyOf(v) == "drive.speed_levels");
  v = {};
  v.body.radius = kNaN;
  CHECK(KeyOf(v) == "body.radius");
  v = {};
  v.camera.fov_deg = 180.0;
  CHECK(KeyOf(v) == "camera.fov_deg");
  v = {};
  v.camera.source = haptel::CameraSourceKind::kDevice;  // and no device
  CHECK(KeyOf(v) == "camera.device");
  v = {};
  v.camera.source = haptel::CameraSourceKind::kFile;  // and no file
  CHECK(KeyOf(v) == "camera.file");
  v = {};
  v.name = "robot 1";
  CHECK(KeyOf(v) == "name");
  v = {};
  v.link.peers = {"127.0.0.1", "localhost"};
  const ConfigFieldError peer = ErrorOf(v);
  CHECK(peer.key == "link.peers[1]");
  CHECK_THAT(peer.expected, Contains("IPv4"));

  haptel::LinkConfig l;
  l.domain_id = 233;
  CHECK(KeyOf(l) == "domain_id");
  l = {};
  l.command_deadline_s = kNaN;
  CHECK(KeyOf(l) == "command_deadline_s");
}

TEST_CASE("DeviceConfig and its parts", "[config][validate]") {
  CHECK_NOTHROW(haptel::ServoLoopConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::SafetyConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::SimArmConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::UdpArmEndpoint{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::UdpDeviceConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::ReplayDeviceConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::DeviceConfig{}.ValidateOrThrow());

  haptel::DeviceConfig d;
  d.servo.rate_hz = 50.0;
  CHECK(KeyOf(d) == "servo.rate_hz");
  d = {};
  d.safety.max_force_rate = kNaN;
  CHECK(KeyOf(d) == "safety.max_force_rate");
  d = {};
  d.safety.fade_s = 0.04;  // 20 ms + 40 ms: forces not gone 50 ms after a stall
  const ConfigFieldError stall = ErrorOf(d);
  CHECK(stall.key == "safety.fade_s");
  CHECK(stall.related == std::vector<std::string>{"safety.setpoint_timeout_s"});
  d = {};
  d.sim.workspace_max[1] = d.sim.workspace_min[1];
  CHECK(KeyOf(d) == "sim.workspace_max");
  d = {};
  d.udp.arms[1].port = 70000;
  CHECK(KeyOf(d) == "udp.right.port");
  d = {};
  d.driver = "udp";  // and no ports
  d.sides = {false, true};
  const ConfigFieldError port = ErrorOf(d);
  CHECK(port.key == "udp.right.port");
  CHECK_THAT(port.expected, Contains("127.0.0.1:0"));
  d = {};
  d.driver = "replay";  // and no trace
  CHECK(KeyOf(d) == "replay.trace");
  d = {};
  d.sides = {false, false};
  CHECK(KeyOf(d) == "sides");
  d = {};
  d.driver = "serial";
  CHECK(KeyOf(d) == "driver");
}

TEST_CASE("RunConfig, OperatorConfig, ScenePlacement", "[config][validate]") {
  CHECK_NOTHROW(haptel::OperatorConfig{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::ScenePlacement{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::RunConfig{}.ValidateOrThrow());

  haptel::RunConfig r;
  r.op.lookahead = 0.0;
  CHECK(KeyOf(r) == "operator.lookahead");
  r = {};
  r.session_rate_hz = kNaN;
  CHECK(KeyOf(r) == "session_rate_hz");
  r = {};
  r.op.cruise = 0.3;  // below min_forward (0.35)
  const ConfigFieldError slow = ErrorOf(r);
  CHECK(slow.key == "operator.min_forward");
  CHECK(slow.expected == "min_forward <= cruise");
  r = {};
  r.interfaces.assign(7, "gesture");  // keys F1-F6
  CHECK(KeyOf(r) == "switchable_interfaces");
  r = {};
  r.scene_placement.position.x() = 500.0;
  CHECK(KeyOf(r) == "scene_placement.position");
  r = {};
  r.scene_placement.rotation(0, 0) = 2.0;  // not a rotation
  CHECK(KeyOf(r) == "scene_placement.rotation");
  r = {};
  r.link.domain_id = -1;
  CHECK(KeyOf(r) == "link.domain_id");
}

TEST_CASE("DeviceCalibration, ArmCalibration", "[config][validate]") {
  CHECK_NOTHROW(haptel::ArmCalibration{}.ValidateOrThrow());
  CHECK_NOTHROW(haptel::DeviceCalibration{}.ValidateOrThrow());

  haptel::DeviceCalibration c;
  c.arms[1].glove_gain[3] = 0.0;
  const ConfigFieldError zero = ErrorOf(c);
  CHECK(zero.key == "arms.right.glove_gain[3]");
  CHECK(zero.expected == "a non-zero number in [-1000, 1000]");
  c = {};
  c.arms[0].tracker_offset[2] = kInf;
  CHECK(KeyOf(c) == "arms.left.tracker_offset[2]");
  c = {};
  c.arms[0].finger_force_slope = -1.0;
  CHECK(KeyOf(c) == "arms.left.finger_force_slope");
  c = {};
  c.arms[1].force_residual = kNaN;
  CHECK(KeyOf(c) == "arms.right.force_residual");
}

TEST_CASE("GravityGridData", "[config][validate]") {
  // A default grid has no vertices: it is data to fill in, not a grid.
  CHECK(KeyOf(haptel::GravityGridData{}) == "counts");
  CHECK_NOTHROW(Grid().ValidateOrThrow());

  haptel::GravityGridData g = Grid();
  g.counts[0] = 1001;
  CHECK(KeyOf(g) == "counts");
  g = Grid();
  g.force_z[5] = kNaN;
  CHECK(KeyOf(g) == "force_z[5]");
  g = Grid();
  g.force_z.pop_back();
  const ConfigFieldError count = ErrorOf(g);
  CHECK(count.key == "force_z");
  CHECK(count.got == "7");
  g = Grid();
  g.max[2] = g.min[2];
  CHECK(KeyOf(g) == "max");
}

TEST_CASE("Loaders put a ValidateOrThrow error at its key, or where the file should have it",
          "[config][validate]") {
  SECTION("a key in a nested section: at its line, with its value") {
    const fs::path f = Write("hand.yaml", "hand:\n  palm_mass: 0.35\n  phalanx_radius: 0.2\n");
    const std::string msg = LoadErrorOf([&] { haptel::LoadPhysics(f); });
    CHECK_THAT(msg, Contains(f.string() + ":3:"));
    CHECK_THAT(msg, Contains("key 'hand.phalanx_radius': expected a number in [0.001, 0.05], "
                             "got '0.2'"));
  }
  SECTION("a key of a list element: at the element's line") {
    const fs::path f = Write("gates.yaml",
                             "name: loop\ncorridor_width: 1.0\n"
                             "centerline: [[0, 0], [4, 0], [4, 3], [0, 3]]\n"
                             "gates:\n  - {along: 2.0}\n  - {along: 6.0, width: 30}\n");
    const std::string msg = LoadErrorOf([&] { haptel::LoadTrack(f); });
    CHECK_THAT(msg, Contains(f.string() + ":6:"));
    CHECK_THAT(msg, Contains("key 'gates[1].width': expected a number in [0.05, 20], got '30'"));
  }
  SECTION("a rule broken by a default: at the other key of the rule the file sets") {
    // phalanx_radius 0.012 is in range; the default distal phalanx (22 mm) is too short for it.
    const fs::path f = Write("rule.yaml", "step_s: 0.001\nhand:\n  phalanx_radius: 0.012\n");
    const std::string msg = LoadErrorOf([&] { haptel::LoadPhysics(f); });
    CHECK_THAT(msg, Contains(f.string() + ":3:"));
    CHECK_THAT(msg, Contains("key 'hand.phalanx_radius': expected every phalanx_length >= 2 * "
                             "phalanx_radius"));
    CHECK_THAT(msg, Contains("got '0.012'"));
  }
  SECTION("a key the file does not have: at the enclosing section, saying so") {
    const std::string text = "name: robot1\ncamera:\n  width: 320\n  source: device\n";
    const fs::path f = Write("camera.yaml", text);
    const std::string msg = LoadErrorOf([&] { haptel::LoadVehicle(f); });
    CHECK_THAT(msg, Contains(f.string() + ":3:"));  // the camera section's first key
    CHECK_THAT(msg, Contains("key 'camera.device'"));
    CHECK_THAT(msg, Contains("but it is missing"));
  }
  SECTION("what a rule found, when the value does not show it") {
    const fs::path f = Write("grid.yaml",
                             "min: [0, 0, 0]\nmax: [1, 1, 1]\ncounts: [2, 2, 3]\n"
                             "force_z: [1, 2, 3, 4, 5, 6, 7, 8]\n");
    const std::string msg = LoadErrorOf([&] { haptel::LoadGravityGrid(f); });
    CHECK_THAT(msg, Contains(f.string() + ":4:"));
    CHECK_THAT(msg, Contains("key 'force_z': expected 12 forces in newtons (2*2*3, x fastest), "
                             "got 8"));
  }
  SECTION("a list value is shown as written") {
    const fs::path f = Write("neutral.yaml", "name: gesture\nneutral: [0.0, 5.0, 0.0]\n");
    CHECK_THAT(LoadErrorOf([&] { haptel::LoadGesture(f); }),
               Contains(":2:") && Contains("key 'neutral': expected a list of 3 numbers in "
                                           "[-1, 1], got [0.0, 5.0, 0.0]"));
  }
}
