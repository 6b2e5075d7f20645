// The session's view part on its own: the overlay it feeds the view (the HUD
// exactly as the interface computed it, the lap clock, the last contact), the
// world's shapes (the wheel turns with the controls, the hands, the wall) and
// each vehicle's picture, whole, on the screen and its fleet tile.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "../interfaces/hal_fixture.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/track.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/gamepad.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/interfaces/keyboard.hpp"
#include "haptel/mediator/notice_log.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/session_view.hpp"
#include "haptel/mediator/world_shapes.hpp"
#include "haptel/video/frame.hpp"
#include "haptel/view/renderer.hpp"

using namespace haptel;
using namespace haptel::mediator;
using haptel::test::Metres;

namespace {

struct PlainPort final : interfaces::ControlsPort {
  interfaces::CockpitControls state;
  interfaces::CockpitControls Controls() const override { return state; }
  void Actuate(const interfaces::ControlActuation&) override {}
};

CockpitConfig Shipped(const char* name) {
  return LoadCockpit(ShippedFile(std::string("config/interfaces/") + name + ".yaml"));
}

/// A vehicle's video that hands one picture, as a receiver hands its latest.
struct OnePicture final : video::FrameSource {
  video::Frame frame;
  video::Frame Latest() const override { return frame; }
};

InterfaceSet One(std::unique_ptr<interfaces::MediatorInterface> i) {
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> v;
  v.push_back(std::move(i));
  return InterfaceSet(std::move(v), 0, 0.3);
}

}  // namespace

TEST_CASE("the overlay's HUD is the HUD cockpit's own, and only a HUD interface shows one") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  setup.operator_kind = "person";
  setup.time_limit_s = 600.0;
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  PlainPort port;
  port.state.wheel_angle = 0.6;  // turned left
  port.state.throttle = 0.03;
  const interfaces::VehicleFeedback feedback{false, false, 0.2345};

  auto hud_cockpit = std::make_unique<interfaces::CockpitInterface>(Shipped("cockpit-hud"), port);
  const interfaces::CockpitInterface& cockpit = *hud_cockpit;
  InterfaceSet hud_set = One(std::move(hud_cockpit));
  const TreadCommand motors = hud_set.Update(1.0, feedback, hal);
  OverlayFeed feed(setup, track);
  const view::Overlay o = feed.Make(12.0, lap, hud_set, feedback, motors, true, false);
  CHECK(o.hud);
  CHECK(o.speed_mps == cockpit.hud().speed);
  CHECK(o.turn_left == cockpit.hud().turn_left);
  CHECK(o.turn_right == cockpit.hud().turn_right);
  CHECK(o.turn_left);
  CHECK(std::string(o.interface_name) == "cockpit-hud");
  CHECK(std::string(o.operator_name) == "person");
  CHECK(o.time_left_s == Approx(588.0));
  CHECK(o.gates_total == static_cast<int>(track.gates().size()));
  const auto lines = view::OverlayLines(o);
  CHECK(std::find(lines.begin(), lines.end(), "speed 0.23 m/s") != lines.end());

  InterfaceSet plain_set =
      One(std::make_unique<interfaces::CockpitInterface>(Shipped("cockpit"), port));
  const TreadCommand plain_motors = plain_set.Update(1.0, feedback, hal);
  OverlayFeed plain_feed(setup, track);
  const view::Overlay p =
      plain_feed.Make(12.0, lap, plain_set, feedback, plain_motors, true, false);
  CHECK_FALSE(p.hud);
  CHECK(view::HudSpeedText(p).empty());
}

TEST_CASE(
    "a practice lap on the keyboard alone: the hint offers no switching, the title says whose "
    "practice") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  setup.operator_kind = "person";
  setup.run.name = "default";
  LapTimer lap(track);
  interfaces::InputBox input;
  InterfaceSet set =
      One(std::make_unique<interfaces::KeyboardInterface>(KeyboardConfig{}, input, 8));
  const TreadCommand still{};
  OverlayFeed switching(setup, track);
  CHECK(std::string(switching.Make(1.0, lap, set, {}, still, true, false).message).find("F1-F6") !=
        std::string::npos);
  CHECK(ViewOptionsFor(setup).title == "Haptel - default");
  setup.single_interface = true;
  setup.title = "Haptel - practice lap - P3";
  OverlayFeed practice(setup, track);
  const std::string hint = practice.Make(1.0, lap, set, {}, still, true, false).message;
  CHECK(hint.find("W/A/S/D") != std::string::npos);
  CHECK(hint.find("F1") == std::string::npos);
  CHECK(ViewOptionsFor(setup).title == "Haptel - practice lap - P3");
}

TEST_CASE(
    "with gesture-shared the overlay carries what pushes the hand; plain gesture shows none") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  test::PutHand(hal, {0.09, 0.0, 0.0});  // full ahead
  // A wall 0.4 m ahead, seen by the beam straight ahead and its neighbours.
  interfaces::VehicleFeedback feedback;
  feedback.ranges.count = 3;
  feedback.ranges.angle_min = -0.1;
  feedback.ranges.angle_increment = 0.1;
  feedback.ranges.range_max = 1.5;
  feedback.ranges.ranges = {0.402f, 0.4f, 0.402f};
  const GestureConfig config = LoadGesture(ShippedFile("config/interfaces/gesture-shared.yaml"));
  auto shared = std::make_unique<interfaces::GestureInterface>(config);
  const interfaces::GestureInterface& gesture = *shared;
  InterfaceSet set = One(std::move(shared));
  const TreadCommand motors = set.Update(1.0, feedback, hal);
  OverlayFeed feed(setup, track);
  const view::Overlay o = feed.Make(1.0, lap, set, feedback, motors, true, false);
  REQUIRE(gesture.guidance().active);
  CHECK(o.guidance_shown);
  CHECK(o.guidance_forward_n == gesture.guidance().force[0]);
  CHECK(o.guidance_forward_n < 0.0);  // back, away from the wall
  CHECK(o.guidance_max_n == config.shared_control.max_force);
  CHECK(o.guidance_ttc_s == Approx(gesture.guidance().time_to_collision_s));
  CHECK(o.hud);  // gesture's speedometer stays

  InterfaceSet plain = One(std::make_unique<interfaces::GestureInterface>(GestureConfig{}));
  const view::Overlay p =
      feed.Make(1.0, lap, plain, feedback, plain.Update(1.0, feedback, hal), true, false);
  CHECK_FALSE(p.guidance_shown);
}

TEST_CASE(
    "with cockpit-shared the overlay carries what pushes the lever and the wheel, as "
    "gesture-shared's") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  PlainPort port;
  port.state = {.wheel_angle = 0.0,
                .throttle = 0.06,
                .wheel_held = true,
                .throttle_held = true};  // full ahead
  interfaces::VehicleFeedback feedback;  // the wall 0.4 m ahead of the gesture-shared case
  feedback.ranges.count = 3;
  feedback.ranges.angle_min = -0.1;
  feedback.ranges.angle_increment = 0.1;
  feedback.ranges.range_max = 1.5;
  feedback.ranges.ranges = {0.402f, 0.4f, 0.402f};
  const CockpitConfig config = Shipped("cockpit-shared");
  auto shared = std::make_unique<interfaces::CockpitInterface>(config, port);
  const interfaces::CockpitInterface& cockpit = *shared;
  InterfaceSet set = One(std::move(shared));
  const TreadCommand motors = set.Update(1.0, feedback, hal);
  OverlayFeed feed(setup, track);
  const view::Overlay o = feed.Make(1.0, lap, set, feedback, motors, true, false);
  REQUIRE(cockpit.guidance().active);
  CHECK(o.guidance_shown);
  CHECK(o.guidance_forward_n == cockpit.guidance().force[0]);
  CHECK(o.guidance_forward_n < 0.0);  // the lever back, towards slower
  CHECK(o.guidance_max_n == config.shared_control.max_force);
  CHECK(o.guidance_ttc_s == Approx(cockpit.guidance().time_to_collision_s));
  CHECK_FALSE(o.hud);  // the plain cockpit's view: no speedometer

  PlainPort plain_port = port;
  InterfaceSet plain =
      One(std::make_unique<interfaces::CockpitInterface>(Shipped("cockpit"), plain_port));
  const view::Overlay p =
      feed.Make(1.0, lap, plain, feedback, plain.Update(1.0, feedback, hal), true, false);
  CHECK_FALSE(p.guidance_shown);
}

TEST_CASE("the overlay remembers the last contact and says when the vehicle is not up yet") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  setup.operator_kind = "auto";
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  GestureConfig gesture;
  InterfaceSet set = One(std::make_unique<interfaces::GestureInterface>(gesture));
  OverlayFeed feed(setup, track);
  const TreadCommand still{};
  view::Overlay o = feed.Make(0.5, lap, set, {}, still, false, false);
  CHECK(std::string(o.message).find("waiting for vehicle") != std::string::npos);
  CHECK(o.time_left_s < 0);  // no limit
  CHECK(std::string(o.last_contact).empty());
  o = feed.Make(3.25, lap, set, {true, false, 0.1}, still, true, true);
  CHECK(o.contact_now);
  CHECK(std::string(o.last_contact) == "left bumper at 3.2 s");
  o = feed.Make(5.0, lap, set, {}, still, true, false);
  CHECK_FALSE(o.contact_now);
  CHECK(std::string(o.last_contact) == "left bumper at 3.2 s");
  CHECK(std::string(o.message).empty());
  // The gesture interface keeps the speedometer and indicators (as the thesis did).
  o = feed.Make(6.0, lap, set, {false, false, 0.2}, {0.1, 0.5}, true, false);
  CHECK(o.hud);
  CHECK(o.turn_left);
  CHECK_FALSE(o.turn_right);
}

TEST_CASE(
    "world shapes: the wheel turns with the controls' angle, held controls are lit, the wall faces "
    "its normal") {
  const CockpitConfig cockpit = Shipped("cockpit");
  const physics::ControlsBodyConfig bodies;
  interfaces::CockpitControls controls;
  std::vector<view::Shape> straight, turned;
  AppendCockpit(straight, cockpit, bodies, controls, false);
  controls.wheel_angle = M_PI / 2;  // a quarter turn left
  controls.wheel_held = true;
  AppendCockpit(turned, cockpit, bodies, controls, false);
  REQUIRE(straight.size() == turned.size());
  REQUIRE(straight.size() == static_cast<size_t>(bodies.rim_segments + 3 + 1 + 2));
  // The rim segment at the top (largest z) ends up on the left (largest y).
  auto top =
      std::max_element(straight.begin(), straight.begin() + bodies.rim_segments,
                       [](const auto& a, const auto& b) { return a.position[2] < b.position[2]; });
  const size_t k = static_cast<size_t>(top - straight.begin());
  const double r = cockpit.wheel_radius;
  CHECK(straight[k].position[2] - cockpit.wheel_hub[2] == Approx(r).epsilon(0.05));
  CHECK(turned[k].position[1] - cockpit.wheel_hub[1] == Approx(r).epsilon(0.05));
  CHECK(turned[k].color.b > straight[k].color.b);  // held: lit blue
  // The lever's knob sits at the throttle position along x.
  controls.throttle = 0.04;
  std::vector<view::Shape> lever;
  AppendCockpit(lever, cockpit, bodies, controls, false);
  CHECK(lever.back().position[0] == Approx(cockpit.throttle_centre[0] + 0.04));

  haptics::ForceField field;
  field.wall_active = true;
  field.wall_point = {0.1, 0.0, 0.0};
  field.wall_normal = {0.0, 1.0, 0.0};
  std::vector<view::Shape> wall;
  AppendWall(wall, field);
  REQUIRE(wall.size() == 1);
  // The slab's thin local x axis is the normal: rotate x by the quaternion.
  const auto& q = wall[0].orientation;
  const double x_y = 2 * (q[1] * q[2] + q[0] * q[3]);  // y component of R·x̂
  CHECK(x_y == Approx(1.0).margin(1e-9));
  CHECK(wall[0].color.a < 1.0f);

  // A bent hand (the mouse): a ghost at the pointer's place, a line to the
  // hand once they part; a force arrow along the force; a shake moves shapes.
  haptics::PseudoHapticReport bent;
  bent.target = {0.05, 0.0, 0.0};
  bent.hand = {0.035, 0.0, 0.0};
  bent.held = true;
  std::vector<view::Shape> ghost;
  AppendPseudoHaptics(ghost, bent);
  REQUIRE(ghost.size() == 2);
  CHECK(ghost[0].kind == view::ShapeKind::kSphere);
  CHECK(ghost[0].position[0] == Approx(0.05));
  CHECK(ghost[0].color.a < 1.0f);
  CHECK(ghost[1].position[0] == Approx(0.0425));  // the line's middle
  bent.hand = bent.target;
  ghost.clear();
  AppendPseudoHaptics(ghost, bent);
  CHECK(ghost.size() == 1);
  std::vector<view::Shape> arrow;
  AppendForceArrow(arrow, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.01});
  CHECK(arrow.empty());  // too small to show
  AppendForceArrow(arrow, {0.0, 0.0, 0.0}, {-5.0, 0.0, 0.0});
  REQUIRE(arrow.size() == 2);
  CHECK(arrow[1].position[0] == Approx(-0.05));  // 1 cm a newton: the head
  ShiftShapes(arrow, 1, {0.0, 0.0, 0.01});
  CHECK(arrow[0].position[2] == 0.0);
  CHECK(arrow[1].position[2] == Approx(0.01));

  physics::HandPoses poses;
  poses.valid = true;
  std::vector<view::Shape> hand;
  AppendProxyHand(hand, poses, ProxyHandConfig{}, haptics::Side::kRight);
  CHECK(hand.size() == 1 + static_cast<size_t>(physics::kFingers * physics::kPhalanges));
  CHECK(hand[0].kind == view::ShapeKind::kBox);
  CHECK(hand[0].position[0] ==
        Approx(ProxyHandConfig{}.palm_half_extents[0]));  // half a palm ahead of the wrist
}

TEST_CASE(
    "a fleet's tiles and its big screen take each vehicle's picture whole: a stale one stays "
    "marked stale",
    "[view]") {
  // The receiver hands an old picture marked stale while a key frame is
  // awaited; the tile's copy once dropped the mark.
  haptics::Hal hal(Metres());
  OnePicture fresh, stale;
  fresh.frame = {std::make_shared<const cv::Mat>(48, 64, CV_8UC3, cv::Scalar(0, 200, 0)), 12, 1'000,
                 false, 3'000};
  stale.frame = {std::make_shared<const cv::Mat>(48, 64, CV_8UC3, cv::Scalar(0, 0, 200)), 7, 500,
                 true, 900};
  std::vector<SessionView::Parts> fleet(2);
  for (SessionView::Parts& parts : fleet) {
    parts.hal = &hal;
    parts.hands = {false, false};
  }
  fleet[0].video = &fresh;
  fleet[1].video = &stale;
  view::ViewOptions options;
  options.mode = view::ViewMode::kOffscreen;
  interfaces::InputBox input;
  SessionView session_view(options, fleet, input);
  view::Tiles tiles;
  tiles.count = 2;
  session_view.Publish(tiles);

  view::ViewModel model;
  session_view.Fill(model);
  const auto same = [](const video::Frame& a, const video::Frame& b) {
    return a.image == b.image && a.id == b.id && a.capture_wall_ns == b.capture_wall_ns &&
           a.stale == b.stale && a.decoded_wall_ns == b.decoded_wall_ns;
  };
  CHECK(same(model.tile_video[0], fresh.frame));
  CHECK(same(model.tile_video[1], stale.frame));
  CHECK(model.tile_video[1].stale);
  CHECK(same(model.video, fresh.frame));  // the first is on the big screen
  session_view.Show(1);
  session_view.Fill(model);
  CHECK(same(model.video, stale.frame));
  CHECK(model.video.stale);
  CHECK(model.tile_video[1].stale);
}

TEST_CASE(
    "no game controller: the person reads it on screen at once, and the log says it once it "
    "lasts") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  setup.operator_kind = "person";
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  interfaces::InputBox input;  // nothing plugged in
  InterfaceSet set = One(std::make_unique<interfaces::GamepadInterface>(GamepadConfig{}, input));
  OverlayFeed feed(setup, track);
  const TreadCommand still{};
  CHECK(std::string(feed.Make(0.5, lap, set, {}, still, true, false).message) ==
        interfaces::kNoControllerNotice);
  CHECK(std::string(feed.Make(40.0, lap, set, {}, still, true, false).message) ==
        interfaces::kNoControllerNotice);  // not only in the help's first seconds

  NoticeLog log;
  CHECK(log.Update(0.0, set.current().Notice()) == nullptr);  // the controller may open yet
  const char* said = log.Update(1.5, set.current().Notice());
  REQUIRE(said != nullptr);
  CHECK(std::string(said) == interfaces::kNoControllerNotice);
  CHECK(log.Update(2.0, set.current().Notice()) == nullptr);  // once

  interfaces::InputState plugged = input.Load();
  plugged.pad_connected = true;
  input.Store(plugged);
  CHECK(set.current().Notice() == nullptr);
  CHECK(std::string(feed.Make(40.0, lap, set, {}, still, true, false).message).empty());
  CHECK(log.Update(3.0, set.current().Notice()) == nullptr);
}

TEST_CASE("back from a cockpit to gesture, the view draws no wheel and no lever") {
  const Track track(LoadTrack(ShippedFile("config/tracks/test-short.yaml")));
  SessionSetup setup;
  setup.operator_kind = "person";
  LapTimer lap(track);
  haptics::Hal hal(Metres());
  const CockpitConfig cockpit = Shipped("cockpit");
  const PhysicsConfig physics_config;
  // The world a cockpit was built with: it stays after the switch.
  std::unique_ptr<SessionPhysics> physics =
      SessionPhysics::CreateIfNeeded(physics_config, {true, true}, &cockpit, nullptr);
  REQUIRE(physics);
  REQUIRE(physics->port);
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> list;
  list.push_back(std::make_unique<interfaces::CockpitInterface>(cockpit, *physics->port));
  list.push_back(std::make_unique<interfaces::GestureInterface>(GestureConfig{}));
  InterfaceSet set(std::move(list), 0, 0.3);

  SessionView::Parts parts;
  parts.hal = &hal;
  parts.physics = physics.get();
  parts.physics_config = &physics_config;
  parts.cockpit = &cockpit;
  parts.hands = {true, true};
  view::ViewOptions options;
  options.mode = view::ViewMode::kOffscreen;
  interfaces::InputBox input;
  SessionView session_view(options, parts, input);
  OverlayFeed feed(setup, track);
  const auto shapes_now = [&](double t) {
    set.Update(t, {}, hal);
    session_view.Publish(feed.Make(t, lap, set, {}, {}, true, false));
    view::ViewModel model;
    session_view.Fill(model);
    return model.shapes.size();
  };
  std::vector<view::Shape> controls;
  AppendCockpit(controls, cockpit, physics::ControlsBodyConfig{}, {}, false);
  REQUIRE_FALSE(controls.empty());

  const size_t with_cockpit = shapes_now(1.0);
  REQUIRE(set.Request(1, 2.0));
  double t = 2.0;
  while (set.switching() && t < 10.0) shapes_now(t += 0.05);
  REQUIRE(set.current().name() == "gesture");
  const size_t with_gesture = shapes_now(t + 0.05);
  CHECK(with_cockpit - with_gesture == controls.size());  // the hands stay, the controls go
  REQUIRE(set.Request(0, t + 0.1));
  while (set.switching() && t < 20.0) shapes_now(t += 0.05);
  CHECK(shapes_now(t + 0.05) == with_cockpit);  // and come back with the cockpit
}
