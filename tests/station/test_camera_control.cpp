// How a person in the control room steers the camera: the picture dragged
// (what was under the pointer stays under it, whatever the zoom), the wheel
// and keys zoom, keys and a controller's stick pan and tilt at rates that
// slow with the zoom, the camera's ranges hold, space points it home; and
// the lines the station's screen shows.
#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/station/camera_control.hpp"
#include "haptel/station/station_view.hpp"
#include "haptel/view/renderer.hpp"

using namespace haptel;
using haptel::station::CameraControl;
using interfaces::Key;
using interfaces::PadAxis;

namespace {

constexpr double kDeg = 0.017453292519943295;
/// The surveillance camera's: pan ±170°, tilt -80..+10°, zoom to 10x, 60° widest.
const CameraRange kRange{-170 * kDeg, 170 * kDeg, -80 * kDeg, 10 * kDeg, 10.0};

haptics::PointerState Window(int x, int y, bool button) {
  haptics::PointerState p;
  p.window_open = true;
  p.in_window = true;
  p.width_px = 1000;
  p.height_px = 600;
  p.x_px = x;
  p.y_px = y;
  p.grasp_button = button;
  return p;
}

}  // namespace

TEST_CASE(
    "dragging the picture moves the scene with the pointer: a field of view per window "
    "width, less when zoomed in") {
  CameraControl control(kRange, 60.0, {});
  const interfaces::InputState none;
  control.Step(none, Window(500, 300, false), 0.02);
  control.Step(none, Window(500, 300, true), 0.02);  // pressed: the drag starts here
  control.Step(none, Window(600, 250, true), 0.02);  // 100 px right, 50 px up
  // Right: what was left comes into view (pan is positive left); up: what was below.
  CHECK(control.aim().pan == Approx(6.0 * kDeg).epsilon(1e-6));
  CHECK(control.aim().tilt == Approx(-3.0 * kDeg).epsilon(1e-6));
  control.Step(none, Window(900, 250, false), 0.02);  // released: moving does nothing
  CHECK(control.aim().pan == Approx(6.0 * kDeg).epsilon(1e-6));

  control.Set({0.0, 0.0, 3.0});
  const double fov = ZoomedFovDeg(60.0, 3.0);
  CHECK(fov == Approx(21.79).margin(0.01));
  control.Step(none, Window(500, 300, true), 0.02);
  control.Step(none, Window(600, 300, true), 0.02);
  CHECK(control.aim().pan == Approx(0.1 * fov * kDeg).epsilon(1e-6));
}

TEST_CASE(
    "the wheel zooms a notch at a time; Page Up and Down, the triggers zoom by a rate; "
    "the lens's range holds") {
  CameraControl control(kRange, 60.0, {});
  const interfaces::InputState none;
  haptics::PointerState p = Window(10, 10, false);
  control.Step(none, p, 0.02);
  p.wheel_notches = 4;
  control.Step(none, p, 0.02);
  CHECK(control.aim().zoom == Approx(std::pow(CameraControl::kWheelZoomStep, 4)));
  p.wheel_notches = 100;  // far past the lens
  control.Step(none, p, 0.02);
  CHECK(control.aim().zoom == Approx(10.0));

  control.Set({0.0, 0.0, 1.0});
  interfaces::InputState keys;
  keys.keys_held[static_cast<size_t>(Key::kPageUp)] = true;
  for (int i = 0; i < 50; ++i) control.Step(keys, p, 0.02);  // 1 s: ×2
  CHECK(control.aim().zoom == Approx(2.0).epsilon(1e-6));

  interfaces::InputState pad;
  pad.pad_connected = true;
  pad.pad_axes[static_cast<size_t>(PadAxis::kTriggerLeft)] = 1.0;
  for (int i = 0; i < 25; ++i) control.Step(pad, p, 0.02);  // 0.5 s out: ÷√2
  CHECK(control.aim().zoom == Approx(std::sqrt(2.0)).epsilon(1e-6));
}

TEST_CASE("keys and the left stick pan and tilt within the head's range; space points it home") {
  CameraControl control(kRange, 60.0, {});
  const haptics::PointerState p = Window(10, 10, false);
  interfaces::InputState keys;
  keys.keys_held[static_cast<size_t>(Key::kArrowLeft)] = true;
  keys.keys_held[static_cast<size_t>(Key::kW)] = true;
  for (int i = 0; i < 50; ++i) control.Step(keys, p, 0.02);  // 1 s at half a field of view
  CHECK(control.aim().pan == Approx(30.0 * kDeg).epsilon(1e-6));
  CHECK(control.aim().tilt ==
        Approx(10.0 * kDeg).epsilon(1e-6));  // 30° asked; the head stops at 10°

  interfaces::InputState pad;
  pad.pad_connected = true;
  pad.pad_axes[static_cast<size_t>(PadAxis::kLeftX)] = 1.0;  // right, full over
  pad.pad_axes[static_cast<size_t>(PadAxis::kLeftY)] = 0.1;  // in the dead zone
  for (int i = 0; i < 50; ++i) control.Step(pad, p, 0.02);   // 1 s at a field of view
  CHECK(control.aim().pan == Approx(-30.0 * kDeg).epsilon(1e-6));
  CHECK(control.aim().tilt == Approx(10.0 * kDeg).epsilon(1e-6));
  for (int i = 0; i < 500; ++i) control.Step(pad, p, 0.02);
  CHECK(control.aim().pan == Approx(-170.0 * kDeg));

  interfaces::InputState space;
  space.key_presses[static_cast<size_t>(Key::kSpace)] = 1;
  control.Step(space, p, 0.02);
  CHECK(control.aim().pan == 0.0);
  CHECK(control.aim().tilt == 0.0);
  CHECK(control.aim().zoom == 1.0);
}

TEST_CASE("a camera learnt later narrows the aim to its range") {
  CameraControl control({}, 60.0, {1.0, 1.0, 5.0});
  CHECK(control.aim().pan == 0.0);  // nothing known yet: a fixed camera
  control.SetCamera(kRange, 50.0);
  control.Set({1.0, -2.0, 5.0});
  CHECK(control.aim().pan == Approx(1.0));
  CHECK(control.aim().tilt == Approx(-80 * kDeg));
  CHECK(control.aim().zoom == Approx(5.0));
  CHECK(control.FovRad() == Approx(ZoomedFovDeg(50.0, 5.0) * kDeg));
}

TEST_CASE("the station's screen: its camera, where it points and zooms, who holds it; no lap") {
  const view::Overlay o = station::StationOverlay(
      "surveillance", "eve", 12.0, station::StatusText({12 * kDeg, -5 * kDeg, 3.0}),
      "camera surveillance of blimp1 is held by haptel station, ana@lab1 pid 7 since 03:12:45 UTC");
  const std::vector<std::string> lines = view::OverlayLines(o);
  REQUIRE(lines.size() == 3);
  CHECK(lines[0] == "station: surveillance  (eve)");
  CHECK(lines[1] == "pan +12.0 tilt -5.0 zoom 3.0x");
  CHECK(lines[2].find("is held by haptel station, ana@lab1") != std::string::npos);
  // A run's overlay keeps its lap lines.
  view::Overlay lap;
  CHECK(view::OverlayLines(lap).size() == 4);
}

TEST_CASE("the station's screen says where the vehicle is, whatever its family") {
  // The blimp's state, read through the family table as the station reads it.
  msg::BlimpState blimp;
  blimp.seq(7);
  blimp.pose_valid(true);
  blimp.x(12.34f);
  blimp.y(-4.5f);
  blimp.z(3.2f);
  blimp.yaw(static_cast<float>(-90 * kDeg));
  blimp.vx(1.2f);
  blimp.vy(1.6f);
  blimp.failsafe(true);
  const link::VehicleGlance flying = link::BlimpMessages::Glance(blimp);
  // The family the vehicle's status names picks the messages.
  CHECK(link::ForFamily(VehicleFamily::kBlimp, []<class M>() { return M::kFamily; }) ==
        VehicleFamily::kBlimp);
  CHECK(link::ForFamily(VehicleFamily::kRobot, []<class M>() { return M::kFamily; }) ==
        VehicleFamily::kRobot);
  CHECK(station::VehicleText("blimp1", flying) ==
        "blimp1 x +12.3 y -4.5 alt 3.2 m hdg 270 2.0 m/s failsafe");
  msg::VehicleState robot;
  robot.seq(3);
  robot.pose_valid(true);
  robot.x(1.0f);
  robot.y(2.0f);
  robot.heading(static_cast<float>(90 * kDeg));
  robot.speed(-0.4f);
  const link::VehicleGlance driving = link::RobotMessages::Glance(robot);
  CHECK(station::VehicleText("robot1", driving) == "robot1 x +1.0 y +2.0 hdg 90 0.4 m/s");
  CHECK(station::VehicleText("robot1", {}).empty());  // no state yet

  // On the screen: the vehicle's line is the status, the camera's leads the message.
  const view::Overlay o = station::StationOverlay(
      "surveillance", "eve", 12.0, station::StatusText({12 * kDeg, -5 * kDeg, 3.0}),
      station::kStationHelp, station::VehicleText("blimp1", flying));
  const std::vector<std::string> lines = view::OverlayLines(o);
  REQUIRE(lines.size() == 3);
  CHECK(lines[1] == "blimp1 x +12.3 y -4.5 alt 3.2 m hdg 270 2.0 m/s failsafe");
  CHECK(lines[2] == std::string("pan +12.0 tilt -5.0 zoom 3.0x  ") + station::kStationHelp);
}
