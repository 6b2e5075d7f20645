// The sdl-ff device through SDL's virtual joystick (SDL_JoystickAttachVirtualEx,
// a test's stand-in for a plugged-in controller; the product never makes
// one): its axes drive the hands, its button is the deadman, its Rumble
// callback receives a contact's shake and a wall pressed, and detaching it
// makes the device lost. A virtual joystick has rumble but no haptic device,
// so these runs take the rumble-only path; the haptic effects' parameters are
// test_ff_model's.
#include <SDL2/SDL.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <functional>
#include <thread>

#include "alloc_counter.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/device_factory.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/haptics/servo_loop.hpp"
#include "haptel/sdl_ff/sdl_ff_device.hpp"
#include "test_env.hpp"
#include "virtual_joystick.hpp"  // tests/support

using namespace haptel;
using namespace haptel::haptics;
using haptel::test::VirtualJoystick;

namespace {

DeviceConfig StickFile() { return LoadDevice("config/devices/sdl-ff.yaml"); }

/// Polls the device's wrist until it answers kOk with a reading `done` takes, or 5 s.
bool WaitForWrist(Device& device, Side side, const std::function<bool(const WristRaw&)>& done) {
  return test::WaitFor(
      [&] {
        WristRaw raw;
        return device.ReadWrist(side, MonotonicNs(), raw) == DeviceStatus::kOk && done(raw);
      },
      5.0);
}

bool WaitFor(const std::function<bool()>& done) { return test::WaitFor(done, 5.0); }

/// One servo tick's worth of what the loop gives the device, stamped now
/// (`contacts`: the vehicle's contacts so far, Hal::MarkContact).
void Feed(Device& device, const ForceField& field, const Vec3d& force, uint64_t contacts = 0) {
  ForceSetpoint sp;
  sp.stamp_ns = MonotonicNs();
  sp.field = field;
  sp.contacts = contacts;
  device.SetpointHint(Side::kRight, sp);
  device.WriteWristForce(Side::kRight, force);
}

}  // namespace

TEST_CASE("sdl-ff on a virtual joystick: the stick moves the hand, the trigger is the deadman") {
  VirtualJoystick stick(/*rumble=*/true);
  const std::unique_ptr<Device> device = MakeDevice(StickFile());
  auto& ff = dynamic_cast<SdlFfDevice&>(*device);
  CHECK(ff.joystick_name() == VirtualJoystick::kName);
  CHECK(ff.rumbles());
  CHECK(DeviceUnavailable(StickFile()).empty());

  // Stick half forward and a quarter right: the hand 5 cm forward, 2.5 cm right.
  stick.SetAxis(1, -16384);
  stick.SetAxis(0, 8192);
  REQUIRE(WaitForWrist(*device, Side::kRight, [](const WristRaw& raw) {
    return std::abs(raw.position[0] - 0.05) < 1e-3 && std::abs(raw.position[1] + 0.025) < 1e-3;
  }));
  CHECK(device->Presence(Side::kRight) == HandPresence::kReleased);
  GloveRaw glove;
  REQUIRE(device->ReadGlove(Side::kRight, MonotonicNs(), glove) == DeviceStatus::kOk);
  CHECK(glove.sensors[5] == 0.0);  // open

  stick.SetButton(0, true);
  REQUIRE(WaitFor([&] { return device->Presence(Side::kRight) == HandPresence::kHeld; }));
  REQUIRE(device->ReadGlove(Side::kRight, MonotonicNs(), glove) == DeviceStatus::kOk);
  CHECK(glove.sensors[5] == 1.6);  // closed on the grip
  stick.SetButton(0, false);
  REQUIRE(WaitFor([&] { return device->Presence(Side::kRight) == HandPresence::kReleased; }));

  // Between two polls the device has nothing new: the loop keeps the last reading.
  WristRaw raw;
  int no_data = 0;
  for (int i = 0; i < 20; ++i) {
    if (device->ReadWrist(Side::kRight, MonotonicNs(), raw) == DeviceStatus::kNoData) ++no_data;
  }
  CHECK(no_data > 0);
}

TEST_CASE("sdl-ff on a virtual joystick with rumble only: a contact and a wall pressed rumble") {
  VirtualJoystick stick(/*rumble=*/true);
  const std::unique_ptr<Device> device = MakeDevice(StickFile());
  stick.SetAxis(1, -16384);  // the hand 5 cm forward
  REQUIRE(WaitForWrist(*device, Side::kRight, [](const WristRaw& raw) {
    return std::abs(raw.position[0] - 0.05) < 1e-3;
  }));
  ForceField field;
  field.enabled = true;
  field.stiffness = 40.0;
  // No contact: the field alone rumbles nothing.
  for (int i = 0; i < 100; ++i) {
    Feed(*device, field, {-2.0, 0.0, 0.0});
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  CHECK(stick.rumbles() == 0);
  CHECK(device->UseReport().shakes == 0);

  // The bumper closes (the session counts the contact): the gesture's wall
  // rises where the hand is, and the hand presses 2 mm into it (3 N of 7).
  field.wall_active = true;
  field.wall_point = {0.048, 0.0, 0.0};
  field.wall_normal = {1.0, 0.0, 0.0};
  field.wall_stiffness = 1500.0;
  REQUIRE(WaitFor([&] {
    Feed(*device, field, {-5.0, 0.0, 0.0}, 1);
    return stick.rumbles() > 0;
  }));
  CHECK(stick.strongest_low() == 39321);  // the shake: 0.6 of full
  CHECK(device->UseReport().shakes == 1);
  // After the shake, the wall pressed rumbles on as hard as it is pressed.
  REQUIRE(WaitFor([&] {
    Feed(*device, field, {-5.0, 0.0, 0.0}, 1);
    return stick.last_low() > 0 && stick.last_low() < 39321 && stick.last_high() == 0;
  }));
  CHECK(std::abs(stick.last_low() - 65535.0 * 3.0 / 7.0) < 700.0);
  CHECK(device->UseReport().ff_effects_played >= 2);
  // The hand leaves the wall: the rumble stops.
  stick.SetAxis(1, 0);
  REQUIRE(WaitFor([&] {
    Feed(*device, field, {0.0, 0.0, 0.0}, 1);
    return stick.last_low() == 0;
  }));
}

TEST_CASE("sdl-ff: a joystick unplugged mid-run makes the device lost") {
  VirtualJoystick stick(/*rumble=*/true);
  const std::unique_ptr<Device> device = MakeDevice(StickFile());
  REQUIRE(WaitForWrist(*device, Side::kRight, [](const WristRaw&) { return true; }));
  stick.Detach();
  REQUIRE(WaitFor([&] {
    WristRaw raw;
    return device->ReadWrist(Side::kRight, MonotonicNs(), raw) == DeviceStatus::kLost;
  }));
  CHECK(device->WriteWristForce(Side::kRight, {1.0, 0.0, 0.0}) == DeviceStatus::kLost);
  CHECK(device->Presence(Side::kRight) == HandPresence::kReleased);
}

TEST_CASE("sdl-ff: no joystick, or none that plays anything, is said plainly") {
  VirtualJoystick::Subsystem sdl;  // the joystick subsystem up, no joystick attached
  DeviceConfig file = StickFile();
  CHECK_THAT(DeviceUnavailable(file), Catch::Contains("no joystick is connected"));
  CHECK_THROWS_WITH(MakeDevice(file), Catch::Contains("config/devices/sdl-ff.yaml") &&
                                          Catch::Contains("sdl_ff.joystick") &&
                                          Catch::Contains("no joystick is connected"));
  {
    VirtualJoystick mute(/*rumble=*/false);
    CHECK_THAT(DeviceUnavailable(file), Catch::Contains("has force feedback or rumble") &&
                                            Catch::Contains(VirtualJoystick::kName));
  }
  VirtualJoystick stick(/*rumble=*/true);
  file.sdl_ff.joystick = 3;
  CHECK_THAT(DeviceUnavailable(file), Catch::Contains("joystick 3 is not there"));
  file.sdl_ff.joystick = -1;
  file.sdl_ff.right.x.axis = 9;  // it has 4
  CHECK_THROWS_WITH(MakeDevice(file),
                    Catch::Contains("sdl_ff.right.x.axis") && Catch::Contains("it has 4"));
}

TEST_CASE("sdl-ff: the servo loop's ticks on the device allocate nothing") {
  VirtualJoystick stick(/*rumble=*/true);
  const DeviceConfig config = StickFile();
  const std::unique_ptr<Device> device = MakeDevice(config);
  DeviceCalibration metres;  // the device calibrates itself
  for (ArmCalibration& arm : metres.arms) arm.tracker_scale = {1.0, 1.0, 1.0};
  Hal hal(metres);
  ServoLoop loop(*device, hal, config, metres);
  ForceField field;
  field.enabled = true;
  field.stiffness = 40.0;
  field.wall_active = true;
  field.wall_point = {0.01, 0.0, 0.0};
  field.wall_stiffness = 1500.0;
  hal.SetField(Side::kRight, field);
  stick.SetAxis(1, -16384);  // into the wall
  const auto tick = [&] {
    const int64_t now = MonotonicNs();
    loop.Tick(Side::kLeft, now);
    loop.Tick(Side::kRight, now);
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  };
  for (int i = 0; i < 20; ++i) tick();  // warm up
  const uint64_t before = test::ThreadAllocations();
  for (int i = 0; i < 200; ++i) tick();
  CHECK(test::ThreadAllocations() == before);
  const HandSample hand = hal.LatestSample(Side::kRight);
  REQUIRE(hand.valid);
  CHECK(hand.position[0] == Approx(0.05).margin(1e-3));  // metres, as the device reports them
  CHECK(hal.presence(Side::kRight) == HandPresence::kReleased);
  CHECK(loop.Counters(Side::kRight).no_data_ticks > 0);  // between the device's polls
}
