// A virtual SDL game controller, seen through InputPump and SdlInput, drives
// GamepadInterface (BlimpManualInterface), whose commands drive the simulated
// robot (blimp) in-process.
// SDL runs for real (its virtual joystick driver: no device, no display);
// the robot is stepped in simulated time, so nothing here depends on timing
// except bounded waits for the pump to deliver what the controller did.
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "haptel/config/blimp_course.hpp"
#include "haptel/interfaces/blimp_manual.hpp"
#include "haptel/interfaces/gamepad.hpp"
#include "haptel/mediator/fleet.hpp"
#include "haptel/models/sim_blimp.hpp"
#include "haptel/models/tread_drive.hpp"
#include "haptel/vehicles/sim_robot.hpp"
#include "haptel/view/head_source.hpp"
#include "haptel/view/sdl_input.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::test::WaitFor;
using haptel::view::InputPump;

namespace {

/// A virtual controller, attached, set and detached on the pump's thread
/// (the thread that owns SDL). Catch's macros stay on the test's thread.
class VirtualPad {
 public:
  explicit VirtualPad(InputPump& pump) : pump_(pump) {
    pump_.RunOnPumpThread([this] {
      const int device =
          SDL_JoystickAttachVirtual(SDL_JOYSTICK_TYPE_GAMECONTROLLER, SDL_CONTROLLER_AXIS_MAX,
                                    SDL_CONTROLLER_BUTTON_MISC1, 0);
      if (device < 0) return;
      id_ = SDL_JoystickGetDeviceInstanceID(device);
      joystick_ = SDL_JoystickOpen(device);
    });
  }
  ~VirtualPad() { Detach(); }
  bool attached() const { return joystick_ != nullptr; }

  /// value in [-1, 1] (sticks) or [0, 1] (triggers), as InputState has it.
  void Axis(SDL_GameControllerAxis axis, double value) {
    const auto raw =
        static_cast<Sint16>(std::lround(std::clamp(value, -1.0, 1.0) * 32767.0) - (value <= -1.0));
    pump_.RunOnPumpThread([&] { SDL_JoystickSetVirtualAxis(joystick_, axis, raw); });
  }
  void Button(SDL_GameControllerButton button, bool down) {
    pump_.RunOnPumpThread([&] { SDL_JoystickSetVirtualButton(joystick_, button, down ? 1 : 0); });
  }
  /// Forgets it without detaching (the pump's SDL_Quit removes it).
  void Abandon() { joystick_ = nullptr; }
  /// Unplugs it.
  void Detach() {
    if (joystick_ == nullptr) return;
    pump_.RunOnPumpThread([this] {
      SDL_JoystickClose(joystick_);
      for (int i = 0; i < SDL_NumJoysticks(); ++i) {
        if (SDL_JoystickGetDeviceInstanceID(i) == id_) SDL_JoystickDetachVirtual(i);
      }
    });
    joystick_ = nullptr;
  }

 private:
  InputPump& pump_;
  SDL_Joystick* joystick_ = nullptr;
  SDL_JoystickID id_ = -1;
};

double AxisOf(const InputState& s, PadAxis a) { return s.pad_axes[static_cast<int>(a)]; }
bool ButtonOf(const InputState& s, PadButton b) { return s.pad_buttons[static_cast<int>(b)]; }

/// An open floor: a wide corridor around a 20 m × 12 m loop, no gates.
TrackConfig Floor() {
  TrackConfig t;
  t.name = "floor";
  t.centerline = {{0, 0}, {20, 0}, {20, 12}, {0, 12}};
  t.corridor_width = 4.0;
  return t;
}

/// The session's part, in simulated time: the interface's command at 50 Hz,
/// quantised to the vehicle's levels, the robot stepped at 200 Hz. Returns
/// how much the heading turned (unwrapped, rad, counter-clockwise +).
double Drive(GamepadInterface& pad, haptics::Hal& hal, vehicles::SimRobot& robot,
             const TreadDriveConfig& drive, double& t, double seconds) {
  double turned = 0.0;
  for (int tick = 0; tick < static_cast<int>(seconds * 50); ++tick, t += 0.02) {
    const TreadCommand m = pad.Update(t, {}, hal);
    robot.SetMotors({models::QuantiseCommand(m.left, drive.speed_levels),
                     models::QuantiseCommand(m.right, drive.speed_levels)});
    for (int i = 0; i < 4; ++i) {
      const double before = robot.State().heading;
      robot.Update(0.005);
      turned += std::remainder(robot.State().heading - before, 2 * std::numbers::pi);
    }
  }
  return turned;
}

}  // namespace

TEST_CASE("a virtual game controller drives the simulated robot, and unplugging it stops the run",
          "[view_input][virtual_pad]") {
  InputBox box;
  InputPump pump(box);
  VirtualPad stick(pump);
  REQUIRE(stick.attached());
  REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));

  GamepadConfig config;  // defaults: left stick, left shoulder is the deadman
  GamepadInterface pad(config, box);
  haptics::Hal hal;
  const Track track(Floor());
  VehicleConfig vehicle;
  vehicle.drive.right_gain = 1.0;  // no drift: straight means straight
  vehicles::SimRobot robot(track, vehicle);
  robot.Place(4.0, 0.0, 0.0);
  double t = 0.0;

  // Stick forward without the deadman: nothing moves.
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTY, -1.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kLeftY) == -1.0; }, 10.0));
  Drive(pad, hal, robot, vehicle.drive, t, 0.5);
  CHECK(robot.State().x == Approx(4.0).margin(1e-9));

  // Deadman held: forward. x grows, the heading stays.
  stick.Button(SDL_CONTROLLER_BUTTON_LEFTSHOULDER, true);
  REQUIRE(WaitFor([&] { return ButtonOf(box.Load(), PadButton::kLeftShoulder); }, 10.0));
  const double turned_straight = Drive(pad, hal, robot, vehicle.drive, t, 2.0);
  CHECK(robot.State().x > 4.0 + 0.4);
  CHECK(std::abs(turned_straight) < 0.02);
  CHECK(std::abs(robot.State().y) < 0.01);

  // Stick half forward and full left: round a left turn (counter-clockwise).
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTX, -1.0);
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTY, -0.5);
  REQUIRE(WaitFor(
      [&] {
        const InputState s = box.Load();
        return AxisOf(s, PadAxis::kLeftX) == -1.0 && AxisOf(s, PadAxis::kLeftY) > -0.6;
      },
      10.0));
  const double turned = Drive(pad, hal, robot, vehicle.drive, t, 3.0);
  CHECK(turned > std::numbers::pi / 2);
  CHECK_FALSE(robot.State().bumper_left);
  CHECK_FALSE(robot.State().bumper_right);

  // Unplugged mid-run: lost, zero command, the robot comes to rest.
  CHECK_FALSE(pad.lost());
  stick.Detach();
  REQUIRE(WaitFor([&] { return box.Load().pad_disconnects == 1; }, 10.0));
  CHECK_FALSE(box.Load().pad_connected);
  CHECK(pad.lost());
  const TreadCommand m = pad.Update(t, {}, hal);
  CHECK(m.left == 0.0);
  CHECK(m.right == 0.0);
  Drive(pad, hal, robot, vehicle.drive, t, 1.0);
  CHECK(std::abs(robot.State().speed) < 1e-3);
}

TEST_CASE("stopping the pump lets the controller go without a disconnect; a new pump starts clean",
          "[view_input][virtual_pad]") {
  InputBox box;
  {
    InputPump first(box);
    VirtualPad stick(first);
    REQUIRE(stick.attached());
    REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));
    stick.Button(SDL_CONTROLLER_BUTTON_A, true);
    REQUIRE(WaitFor([&] { return ButtonOf(box.Load(), PadButton::kA); }, 10.0));
    stick.Abandon();  // SDL_Quit takes the virtual device with it
  }
  InputState s = box.Load();
  CHECK_FALSE(s.pad_connected);
  CHECK_FALSE(ButtonOf(s, PadButton::kA));
  CHECK(s.pad_disconnects == 0);

  // SDL went down with the first pump and comes up again for the second.
  InputPump second(box);
  VirtualPad stick(second);
  REQUIRE(stick.attached());
  REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));
  stick.Detach();
  REQUIRE(WaitFor([&] { return box.Load().pad_disconnects == 1; }, 10.0));
  s = box.Load();
  CHECK_FALSE(s.pad_connected);
}

TEST_CASE(
    "a virtual game controller flies the simulated blimp: climb away, tail-rotor turnabout, unplug",
    "[view_input][virtual_pad][blimp]") {
  InputBox box;
  InputPump pump(box);
  VirtualPad stick(pump);
  REQUIRE(stick.attached());
  REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));

  BlimpManualConfig config;
  config.name = "blimp-gamepad";
  BlimpManualInterface pad(config, box.Load());
  haptics::Hal hal;
  models::SimBlimp blimp(AirshipConfig{}, LoadBlimpCourse("config/tracks/blimp-hop.yaml"));
  double t = 0.0;
  // The session's part in simulated time: the command at 50 Hz, the airship at 200 Hz.
  const auto fly = [&](double seconds) {
    for (int tick = 0; tick < static_cast<int>(seconds * 50); ++tick, t += 0.02) {
      const BlimpCommand c = pad.Update(t, box.Load(), hal);
      for (int i = 0; i < 4; ++i) blimp.Step(0.005, c);
    }
  };
  const double ground = blimp.position().z();

  // Left stick up and the right trigger: power, the helix plane up. Away and up.
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTY, -1.0);
  stick.Axis(SDL_CONTROLLER_AXIS_TRIGGERRIGHT, 0.6);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kTriggerRight) > 0.5; }, 10.0));
  fly(10.0);
  CHECK(blimp.position().x() > 10.0);
  CHECK(blimp.position().z() > ground + 1.0);
  CHECK(blimp.applied().power > 0.8);

  // Stick back to centre, then sideways at zero power: the tail rotor turns it about (left).
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTY, 0.0);
  stick.Axis(SDL_CONTROLLER_AXIS_TRIGGERRIGHT, 0.0);
  fly(8.0);  // coast down to a crawl
  const double yaw_before = blimp.yaw();
  stick.Axis(SDL_CONTROLLER_AXIS_LEFTX, -1.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kLeftX) == -1.0; }, 10.0));
  fly(4.0);
  CHECK(blimp.applied().power == 0.0);
  CHECK(blimp.applied().tail_rotor > 0.8);
  CHECK(std::remainder(blimp.yaw() - yaw_before, 2 * std::numbers::pi) > 0.3);

  // Unplugged: lost, every channel to neutral.
  stick.Detach();
  REQUIRE(WaitFor([&] { return box.Load().pad_disconnects == 1; }, 10.0));
  fly(0.1);
  CHECK(pad.lost());
  CHECK(blimp.applied().tail_rotor == 0.0);
  CHECK(blimp.applied().power == 0.0);
}

TEST_CASE(
    "a virtual game controller's Back button asks a fleet for its next vehicle, once per press",
    "[view_input][virtual_pad]") {
  InputBox box;
  InputPump pump(box);
  VirtualPad stick(pump);
  REQUIRE(stick.attached());
  REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));
  const uint32_t before = box.Load().vehicle_requests;
  stick.Button(SDL_CONTROLLER_BUTTON_BACK, true);
  REQUIRE(WaitFor([&] { return box.Load().vehicle_requests == before + 1; }, 10.0));
  CHECK(box.Load().vehicle_request == kNextVehicle);
  // Held, it asks nothing more; released and pressed again, once more.
  stick.Button(SDL_CONTROLLER_BUTTON_BACK, false);
  REQUIRE(WaitFor([&] { return !ButtonOf(box.Load(), PadButton::kBack); }, 10.0));
  CHECK(box.Load().vehicle_requests == before + 1);
  stick.Button(SDL_CONTROLLER_BUTTON_BACK, true);
  REQUIRE(WaitFor([&] { return box.Load().vehicle_requests == before + 2; }, 10.0));
  // The fleet turns from the driven vehicle to the next whose course is not over.
  CHECK(mediator::RequestedVehicle(box.Load().vehicle_request, 0, {false, true, false}) == 2);
}

TEST_CASE(
    "the head by a game controller: the right stick turns the blimp's camera at a rate, a release "
    "holds it, a click recentres it, an unplugged controller holds it still and says so",
    "[view_input][virtual_pad][head]") {
  InputBox box;
  InputPump pump(box);
  VirtualPad stick(pump);
  REQUIRE(stick.attached());
  REQUIRE(WaitFor([&] { return box.Load().pad_connected; }, 10.0));

  HeadConfig config;  // 1.5 rad/s at full deflection
  view::GamepadHead head(config, box.Load());
  BlimpManualConfig keys;
  keys.name = "blimp-keys";
  BlimpManualInterface pilot(keys, box.Load());
  haptics::Hal hal;
  double t = 0.0;
  view::HeadPose pose;
  // The session's tick at 100 Hz: the head's pose into the person's input,
  // which the interface turns the camera by.
  BlimpCommand command;
  const auto run = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(std::lround(seconds * 100)); ++i, t += 0.01) {
      InputState person = box.Load();
      pose = head.Update(t, person);
      person.head_pan = pose.pan;
      person.head_tilt = pose.tilt;
      command = pilot.Update(t, person, hal);
    }
  };
  run(0.2);
  CHECK(pose.pan == 0.0);
  CHECK(head.Notice() == nullptr);

  // Full right for half a second: the head turns right (pan negative) at 1.5 rad/s.
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTX, 1.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightX) == 1.0; }, 10.0));
  run(0.5);
  CHECK(pose.pan == Approx(-0.75).margin(0.02));
  CHECK(command.camera_pan == Approx(pose.pan));
  CHECK(pose.tilt == 0.0);
  // Released: it stays where it looks.
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTX, 0.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightX) == 0.0; }, 10.0));
  run(0.5);
  CHECK(pose.pan == Approx(-0.75).margin(0.02));
  // Inside the dead zone: no turn.
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTY, 0.1);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightY) > 0.05; }, 10.0));
  run(0.5);
  CHECK(pose.tilt == 0.0);
  // Pushed up (SDL's y negative): it looks up, as far as the camera tilts.
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTY, -1.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightY) == -1.0; }, 10.0));
  run(1.0);
  CHECK(pose.tilt == Approx(kBlimpCameraTiltMax));
  CHECK(command.camera_tilt == Approx(kBlimpCameraTiltMax));
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTY, 0.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightY) == 0.0; }, 10.0));

  // Clicking the stick looks straight ahead.
  stick.Button(SDL_CONTROLLER_BUTTON_RIGHTSTICK, true);
  REQUIRE(WaitFor([&] { return ButtonOf(box.Load(), PadButton::kRightStick); }, 10.0));
  run(0.1);
  CHECK(pose.pan == 0.0);
  CHECK(pose.tilt == 0.0);
  stick.Button(SDL_CONTROLLER_BUTTON_RIGHTSTICK, false);

  // Turned a little, then unplugged: the camera holds still, and the head says why.
  stick.Axis(SDL_CONTROLLER_AXIS_RIGHTX, -1.0);
  REQUIRE(WaitFor([&] { return AxisOf(box.Load(), PadAxis::kRightX) == -1.0; }, 10.0));
  run(0.2);
  const double held = pose.pan;
  CHECK(held == Approx(0.3).margin(0.02));
  stick.Detach();
  REQUIRE(WaitFor([&] { return box.Load().pad_disconnects == 1; }, 10.0));
  run(0.5);
  CHECK(pose.pan == held);
  CHECK(command.camera_pan == Approx(held));
  REQUIRE(head.Notice() != nullptr);
  CHECK(std::string(head.Notice()) == view::GamepadHead::kLostNotice);
}

TEST_CASE("the head by OpenXR with no runtime: one clear line, and the mouse turns the head",
          "[view_input][head]") {
  // Whatever this machine has installed: a runtime file that is not there.
  setenv("XR_RUNTIME_JSON", "/nonexistent/haptel-test-openxr-runtime.json", 1);
  HeadConfig config;
  config.source = HeadSourceKind::kOpenXr;
  InputState person;
  view::MadeHeadSource made = view::MakeHeadSource(config, person);
  unsetenv("XR_RUNTIME_JSON");
  REQUIRE(made.source);
  CHECK(made.source->kind() == HeadSourceKind::kMouse);
  CHECK(made.fallback ==
        "no OpenXR runtime (XR_ERROR_RUNTIME_UNAVAILABLE): head follows the mouse");
  person.head_pan = 0.4;  // the mouse dragged
  person.head_tilt = -0.2;
  const view::HeadPose pose = made.source->Update(1.0, person);
  CHECK(pose.pan == 0.4);
  CHECK(pose.tilt == -0.2);
  CHECK(made.source->Notice() == nullptr);
}

TEST_CASE("an HMD's orientation as the camera's pan and tilt: left and up positive, clamped",
          "[view_input][head]") {
  const double a = 0.5;  // rad
  // About OpenXR's up (+y) by a: looking left.
  view::HeadPose p = view::HeadPoseOfOrientation(0, std::sin(a / 2), 0, std::cos(a / 2));
  CHECK(p.pan == Approx(a));
  CHECK(p.tilt == Approx(0.0).margin(1e-9));
  // About +x by a: looking up.
  p = view::HeadPoseOfOrientation(std::sin(a / 2), 0, 0, std::cos(a / 2));
  CHECK(p.pan == Approx(0.0).margin(1e-9));
  CHECK(p.tilt == Approx(a));
  // Looking straight down: the camera's lowest tilt.
  p = view::HeadPoseOfOrientation(std::sin(-0.8), 0, 0, std::cos(-0.8));
  CHECK(p.tilt == Approx(-kBlimpCameraTiltMax));
}
