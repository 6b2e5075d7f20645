// The mouse device (haptics/mouse): the pointer and keys as hands, the
// forces bending them (pseudo-haptics), driven through the real servo loop
// and HAL in simulated time, with the pointer box a test of its own.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/haptics/calibrated_units.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/mouse/mouse_device.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;

namespace {
constexpr int64_t kMs = 1'000'000;
constexpr int kWidth = 1024;
constexpr int kHeight = 576;

/// The shipped device file, run by hand: no real-time thread, no locked memory.
DeviceConfig ShippedMouse() {
  DeviceConfig c = LoadDevice(ShippedFile("config/devices/mouse.yaml"));
  c.servo.realtime_priority = 0;
  c.servo.lock_memory = false;
  return c;
}

/// A pointer in an open window, at the pixel that puts the pointer hand at `target`.
PointerState PointerAt(const Vec3d& target, const MouseDeviceConfig& config, bool button) {
  PointerState p;
  p.window_open = true;
  p.in_window = true;
  p.width_px = kWidth;
  p.height_px = kHeight;
  const std::array<int, 2> px = PointerPixelFor(target, config, kWidth, kHeight);
  p.x_px = px[0];
  p.y_px = px[1];
  p.grasp_button = button;
  return p;
}

/// The device, HAL and servo loop of a run, ticked by the test.
struct Rig {
  DeviceConfig config = ShippedMouse();
  PointerBox pointer;
  MouseDevice device{config, pointer};
  Hal hal{IdentityCalibration("mouse")};
  ServoLoop loop{device, hal, config, IdentityCalibration("mouse")};
  int64_t now_ns = 0;
  std::optional<ForceField> field;  ///< kept fresh every tick when set

  /// One millisecond of both arms.
  void Tick() {
    now_ns += kMs;
    if (field) {
      hal.SetField(Side::kLeft, *field, now_ns);
      hal.SetField(Side::kRight, *field, now_ns);
    }
    loop.Tick(Side::kLeft, now_ns);
    loop.Tick(Side::kRight, now_ns);
  }
  void Run(double s) {
    for (int i = 0; i < static_cast<int>(s * 1000); ++i) Tick();
  }
  Vec3d Hand(Side side) const { return hal.LatestSample(side).position; }
  const MouseDeviceConfig& mouse() const { return config.mouse; }
};

ForceField Spring(double k, const Vec3d& neutral) {
  ForceField f;
  f.enabled = true;
  f.neutral = neutral;
  f.stiffness = k;
  return f;
}

/// Sets an environment variable for a scope, and puts it back.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    if (value != nullptr) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }

 private:
  const char* name_;
  std::optional<std::string> old_;
};
}  // namespace

TEST_CASE("mouse device: a spring field lets the hand travel k_c/(k_c+k) of the pointer's motion",
          "[mouse]") {
  for (const double k : {40.0, 300.0}) {
    INFO("field stiffness " << k << " N/m");
    Rig rig;
    const Vec3d centre = rig.mouse().centre;
    rig.field = Spring(k, centre);
    rig.pointer.Store(PointerAt(centre, rig.mouse(), true));
    rig.Run(0.6);  // past the soft start
    // Drag 8 cm forward at 0.08 m/s, then hold it there.
    for (int i = 1; i <= 1000; ++i) {
      rig.pointer.Store(
          PointerAt({centre[0] + 0.00008 * i, centre[1], centre[2]}, rig.mouse(), true));
      rig.Tick();
    }
    rig.Run(1.0);
    const double pointer_m = PointerTarget(rig.pointer.Load(), rig.mouse())[0] - centre[0];
    const double kc = rig.mouse().coupling_stiffness;
    CHECK((rig.Hand(Side::kRight)[0] - centre[0]) / pointer_m ==
          Approx(kc / (kc + k)).epsilon(0.03));
    // The record's figure: the hand's motion over the pointer's while it moved.
    CHECK(rig.device.UseReport().pseudo_haptic_gain_mean == Approx(kc / (kc + k)).epsilon(0.15));
    // What the view shows: the pointer's place and the hand's, in metres.
    const Hal::PseudoHaptics shown = rig.hal.pseudo_haptics(Side::kRight);
    REQUIRE(shown.shown);
    CHECK(shown.report.target[0] == Approx(centre[0] + pointer_m));
    CHECK(shown.report.hand[0] == Approx(rig.Hand(Side::kRight)[0]));
    CHECK(shown.report.held);
  }
}

TEST_CASE(
    "mouse device: at the gesture's wall the hand stays near it while the pointer goes "
    "through, and it does not chatter",
    "[mouse]") {
  Rig rig;
  const Vec3d centre = rig.mouse().centre;
  // The shipped gesture's field and its wall after a contact (gesture.cpp).
  ForceField f = Spring(40.0, centre);
  f.stiffness_growth = 300.0;
  f.damping = 2.0;
  f.wall_active = true;
  f.wall_point = {centre[0] + 0.03, centre[1], centre[2]};
  f.wall_normal = {1.0, 0.0, 0.0};
  f.wall_stiffness = 1500.0;
  f.wall_damping = 2.0 * std::sqrt(1500.0);
  rig.field = f;
  rig.pointer.Store(PointerAt(centre, rig.mouse(), true));
  rig.Run(0.6);
  // The pointer goes 20 cm forward in half a second: 17 cm through the wall.
  for (int i = 1; i <= 500; ++i) {
    rig.pointer.Store(PointerAt({centre[0] + 0.0004 * i, centre[1], centre[2]}, rig.mouse(), true));
    rig.Tick();
  }
  rig.Run(0.5);
  double lowest = 1.0, highest = -1.0;
  for (int i = 0; i < 500; ++i) {
    rig.Tick();
    lowest = std::min(lowest, rig.Hand(Side::kRight)[0]);
    highest = std::max(highest, rig.Hand(Side::kRight)[0]);
  }
  INFO("hand between " << lowest << " and " << highest << " m");
  CHECK(highest < centre[0] + 0.03 + 0.015);  // within 1.5 cm of the wall
  CHECK(lowest > centre[0] + 0.03);           // pushed into it, not bounced off
  CHECK(highest - lowest < 1e-4);             // still: no chatter
}

TEST_CASE("mouse device: forces never shake the hand: a force step, a wall rising", "[mouse]") {
  // A cockpit's lever in the hand steps the coupling's force by newtons a
  // tick; the gesture's wall rises on a contact the HAL already counts.
  Rig rig;
  const Vec3d centre = rig.mouse().centre;
  ForceField f = Spring(40.0, centre);
  rig.field = f;
  rig.pointer.Store(PointerAt(centre, rig.mouse(), true));
  rig.Run(0.6);  // past the soft start
  WristRaw wrist;
  for (int t = 1; t < 200; ++t) {
    rig.device.ReadWrist(Side::kRight, rig.now_ns + t * kMs, wrist);
    rig.device.WriteWristForce(Side::kRight, {0.0, t % 2 == 0 ? 3.0 : -3.0, 0.0});
  }
  f.wall_active = true;
  f.wall_point = rig.Hand(Side::kRight);
  f.wall_normal = {1.0, 0.0, 0.0};
  f.wall_stiffness = 1500.0;
  rig.field = f;
  rig.Run(0.5);
  CHECK(rig.device.UseReport().shakes == 0);
  CHECK(rig.hal.pseudo_haptics(Side::kRight).report.shake == Vec3d{});
}

TEST_CASE(
    "mouse device: a contact of the vehicle shakes the pointer hand once, in the servo tick that "
    "reads it, along the wall's normal where one is up; the HAL says when, the trace records it",
    "[mouse]") {
  const auto file = test::ScratchDir("mouse-shake") / "shake.trace";
  Rig rig;
  const Vec3d centre = rig.mouse().centre;
  ForceField f = Spring(40.0, centre);
  rig.field = f;
  rig.pointer.Store(PointerAt(centre, rig.mouse(), true));
  std::vector<int64_t> contact_ns;
  {
    TraceWriter trace(file);
    rig.loop.SetTrace(&trace);
    rig.Run(0.6);
    CHECK(rig.device.UseReport().shakes == 0);
    CHECK(rig.hal.pseudo_haptics(Side::kRight).report.shake_start_ns == 0);
    // The session learns of a bumper: the next servo tick shakes.
    rig.hal.MarkContact();
    contact_ns.push_back(rig.now_ns + kMs);
    rig.Tick();
    // Started in that tick (the HAL publishes the device's report at the next one).
    PseudoHapticReport shown;
    REQUIRE(rig.device.PseudoHaptics(Side::kRight, shown));
    CHECK(shown.shakes == 1);
    CHECK(shown.shake_start_ns == contact_ns.back());
    rig.Run(0.05);
    shown = rig.hal.pseudo_haptics(Side::kRight).report;
    CHECK(shown.shake_start_ns == contact_ns.back());
    CHECK(std::abs(shown.shake[0]) > 0.0);  // backwards: along x only
    CHECK(shown.shake[1] == 0.0);
    CHECK(shown.shake[2] == 0.0);
    rig.Run(1.0);  // nothing new: no more shakes
    CHECK(rig.hal.pseudo_haptics(Side::kRight).report.shakes == 1);
    // A second contact, with the gesture's wall up across y: along its normal.
    f.wall_active = true;
    f.wall_point = rig.Hand(Side::kRight);
    f.wall_normal = {0.0, 1.0, 0.0};
    f.wall_stiffness = 1500.0;
    rig.field = f;
    rig.hal.MarkContact();
    contact_ns.push_back(rig.now_ns + kMs);
    rig.Run(0.05);
    shown = rig.hal.pseudo_haptics(Side::kRight).report;
    CHECK(shown.shakes == 2);
    CHECK(shown.shake_start_ns == contact_ns.back());
    CHECK(shown.shake[0] == 0.0);
    CHECK(std::abs(shown.shake[1]) > 0.0);
    CHECK(std::abs(shown.shake[1]) <= MouseDevice::kMaxShakeM);
    rig.loop.SetTrace(nullptr);
  }  // the writer drains and closes
  // The key hand shows none: a record per contact, the pointer hand's, at its tick.
  std::vector<int64_t> shakes;
  for (const TraceRecord& r : ReadTrace(file)) {
    if (r.kind != TraceRecord::kShake) continue;
    CHECK(r.side == Index(Side::kRight));
    CHECK(r.ToShake().held);
    shakes.push_back(r.t_ns);
  }
  CHECK(shakes == contact_ns);
  CHECK(rig.device.UseReport().shakes == 2);
  CHECK(rig.hal.pseudo_haptics(Side::kLeft).report.shakes == 0);
}

TEST_CASE("mouse device: a side is held only with a window, the pointer in it and the button down",
          "[mouse]") {
  const DeviceConfig config = ShippedMouse();
  PointerBox pointer;
  MouseDevice device(config, pointer);
  WristRaw wrist;
  int64_t t = 0;
  const auto presence = [&](const PointerState& p) {
    pointer.Store(p);
    t += kMs;
    for (const Side side : {Side::kLeft, Side::kRight}) device.ReadWrist(side, t, wrist);
    const HandPresence left = device.Presence(Side::kLeft);
    CHECK(device.Presence(Side::kRight) == left);  // both hands alike
    return left;
  };
  const PointerState held = PointerAt(config.mouse.centre, config.mouse, true);
  CHECK(presence(PointerState{}) == HandPresence::kReleased);  // no window yet
  CHECK(presence(held) == HandPresence::kHeld);
  PointerState p = held;
  p.grasp_button = false;
  CHECK(presence(p) == HandPresence::kReleased);
  p = held;
  p.in_window = false;
  CHECK(presence(p) == HandPresence::kReleased);
  p = held;
  p.window_open = false;
  CHECK(presence(p) == HandPresence::kReleased);
  CHECK(presence(held) == HandPresence::kHeld);
}

TEST_CASE(
    "mouse device: held, both hands close into the cockpit's grip, and the HAL reads "
    "radians and metres",
    "[mouse]") {
  Rig rig;
  rig.pointer.Store(PointerAt(rig.mouse().centre, rig.mouse(), false));
  rig.Run(0.05);
  CHECK(rig.hal.LatestSample(Side::kLeft).finger_angles == std::array<double, kGloveJoints>{});
  rig.pointer.Store(PointerAt(rig.mouse().centre, rig.mouse(), true));
  rig.Run(0.05);
  for (const Side side : {Side::kLeft, Side::kRight}) {
    const HandSample s = rig.hal.LatestSample(side);
    CHECK(s.finger_angles == MouseDevice::ClosedGlove());
    CHECK(s.finger_angles[4 + 1] == Approx(1.6));  // the index's PIP, rad
  }
  // The key hand rests at its rest, in metres, as the device file says.
  const Vec3d left = rig.Hand(Side::kLeft);
  for (int i = 0; i < 3; ++i) CHECK(left[i] == Approx(rig.mouse().key_hand_rest[i]).margin(1e-6));
}

TEST_CASE("mouse device: the key hand moves while its key is held and goes back to rest",
          "[mouse]") {
  Rig rig;
  const Vec3d rest = rig.mouse().key_hand_rest;
  PointerState p = PointerAt(rig.mouse().centre, rig.mouse(), true);
  rig.pointer.Store(p);
  rig.Run(0.1);
  // W for 0.4 s: the target goes 6 cm forward at 0.15 m/s; the hand follows.
  p.key_hand[static_cast<size_t>(KeyHandKey::kPlusX)] = true;
  rig.pointer.Store(p);
  rig.Run(0.4);
  CHECK(rig.hal.pseudo_haptics(Side::kLeft).report.target[0] ==
        Approx(rest[0] + 0.06).margin(1e-3));
  rig.Run(0.3);  // the target is 10.5 cm out now; the hand 5 time constants behind at most
  CHECK(rig.Hand(Side::kLeft)[0] > rest[0] + 0.08);
  CHECK(rig.Hand(Side::kRight)[0] ==
        Approx(rig.mouse().centre[0]).margin(1e-6));  // the other stays
  // Let go of the key: back to rest at the same speed, and there it stays.
  p.key_hand = {};
  rig.pointer.Store(p);
  rig.Run(1.2);
  CHECK(rig.Hand(Side::kLeft)[0] == Approx(rest[0]).margin(1e-4));
  // With the pointer out of the window, the keys move its target but not
  // the hand (no force: it stays).
  p.in_window = false;
  p.key_hand[static_cast<size_t>(KeyHandKey::kMinusY)] = true;
  rig.pointer.Store(p);
  rig.Run(0.3);
  CHECK(rig.hal.pseudo_haptics(Side::kLeft).report.target[1] < rest[1] - 0.03);
  CHECK(rig.Hand(Side::kLeft)[1] == Approx(rest[1]).margin(1e-6));
}

TEST_CASE(
    "mouse device: the button up, the open hand still follows the pointer (to be brought to a "
    "control); out of the window it is free and the field pulls it back to neutral",
    "[mouse]") {
  Rig rig;
  const Vec3d centre = rig.mouse().centre;
  rig.field = Spring(40.0, centre);
  rig.pointer.Store(PointerAt({centre[0], centre[1] - 0.06, centre[2]}, rig.mouse(), false));
  rig.Run(1.5);
  CHECK(rig.Hand(Side::kRight)[1] < centre[1] - 0.03);  // followed, bent by the field
  CHECK(rig.device.Presence(Side::kRight) == HandPresence::kReleased);
  GloveRaw open{};
  rig.device.ReadGlove(Side::kRight, 0, open);
  for (const double s : open.sensors) CHECK(s == 0.0);  // open: not grasping
  // The pointer left the window where it is: the hand drifts back.
  PointerState away = PointerAt({centre[0], centre[1] - 0.06, centre[2]}, rig.mouse(), false);
  away.in_window = false;
  rig.pointer.Store(away);
  rig.Run(2.0);
  CHECK(rig.Hand(Side::kRight)[1] == Approx(centre[1]).margin(0.005));
}

TEST_CASE("mouse device: its servo calls allocate nothing", "[mouse][alloc]") {
  Rig rig;
  ForceField f = Spring(40.0, rig.mouse().centre);
  rig.field = f;
  rig.pointer.Store(PointerAt(rig.mouse().centre, rig.mouse(), true));
  rig.Run(0.01);  // warm up
  const uint64_t before = test::ThreadAllocations();
  for (int i = 0; i < 600; ++i) {
    PointerState p = PointerAt({0.0005 * (i % 100), 0.0, 0.0}, rig.mouse(), i % 200 < 150);
    p.key_hand[0] = i % 50 < 25;
    rig.pointer.Store(p);
    f.wall_active = i % 400 >= 350;  // a wall rises and falls
    rig.field = f;
    // A contact now and then: shakes start and run.
    if (i % 300 == 0) rig.hal.MarkContact();
    rig.Tick();
  }
  (void)rig.device.UseReport();
  CHECK(test::ThreadAllocations() == before);
  CHECK(rig.device.UseReport().shakes > 0);
}

TEST_CASE("mouse driver: without a display it says what is missing", "[mouse]") {
  const DeviceConfig config = ShippedMouse();
  const ScopedEnv wayland("WAYLAND_DISPLAY", nullptr);
  {
    const ScopedEnv display("DISPLAY", nullptr);
    const std::string line = DeviceUnavailable(config);
    CHECK_THAT(line, Catch::Contains("needs a display") && Catch::Contains("DISPLAY"));
  }
  {
    const ScopedEnv display("DISPLAY", ":4711");  // no X server there
    CHECK_THAT(DeviceUnavailable(config), Catch::Contains("DISPLAY=:4711 does not answer"));
  }
  const DeviceDriver* driver = FindDeviceDriver("mouse");
  REQUIRE(driver != nullptr);
  CHECK_FALSE(driver->simulated);
  CHECK(driver->reads_window);
  CHECK(driver->calibration == CalibrationSource::kSelf);
}
