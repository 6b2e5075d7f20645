// End to end with the mouse device (issue 36): a real X server (Xvfb), the
// real `haptel` window, and the pointer pilot (testing/pointer_pilot.hpp)
// moving the real pointer, holding its button and the key hand's keys as a
// person at a mouse would, deciding as the automatic operator does.
#include <algorithm>
#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "child.hpp"
#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/run.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/testing/hand_trace.hpp"
#include "haptel/testing/obstacle_track.hpp"
#include "haptel/testing/pointer_pilot.hpp"
#include "haptel/testing/run_watch.hpp"
#include "haptel/testing/x_desktop.hpp"
#include "haptel/view/sdl_input.hpp"
#include "haptel/view/view.hpp"
#include "test_env.hpp"
#include "xserver.hpp"

using namespace haptel;
using haptel::test::Child;
using haptel::test::JsonField;
using haptel::test::XServer;
using haptel::testing::PilotSetup;
using haptel::testing::PointerApproach;
using haptel::testing::PointerGesture;
using haptel::testing::PointerHands;
using haptel::testing::PointerPilot;

namespace {

std::string Bin(const std::string& name) { return (test::BinDir() / name).string(); }

constexpr const char* kMouse = "config/devices/mouse.yaml";
constexpr const char* kTrack = "config/tracks/test-short.yaml";
constexpr double kLapCap_s = 60.0;  // test-short.yaml's lap_cap_s

/// `haptel run` of a person at the mouse device, in a window, on `domain`.
std::vector<std::string> MouseRun(const std::string& interface, int domain,
                                  const std::string& vehicle, const std::filesystem::path& dir,
                                  std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{Bin("haptel"),
                                "run",
                                "--operator",
                                "person",
                                "--device",
                                kMouse,
                                "--view",
                                "window",
                                "--interface",
                                interface,
                                "--track",
                                kTrack,
                                "--json",
                                "--domain",
                                std::to_string(domain),
                                "--vehicle-name",
                                vehicle,
                                "--database",
                                (dir / "runs.db").string(),
                                "--vehicle-timeout",
                                "5",
                                "--reality",
                                "none"};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

/// Where the screenshots are kept for the docs (docs/haptics.md): build/mouse-screens/.
std::filesystem::path ScreensDir() {
  const auto dir = test::BinDir().parent_path() / "mouse-screens";
  std::filesystem::create_directories(dir);
  return dir;
}

interfaces::HandGoal At(double x, double y, double z) {
  interfaces::HandGoal g;
  g.position = {x, y, z};
  return g;
}

}  // namespace

TEST_CASE("the pointer pilot's hands: a pixel for the pointer hand, keys for the key hand",
          "[pilot]") {
  MouseDeviceConfig mouse;
  mouse.centre = {0.1, 0.0, 0.05};
  mouse.key_hand_rest = {0.0, 0.2, 0.0};
  mouse.key_hand_speed = 0.1;
  PointerHands hands(mouse);
  REQUIRE(hands.pointer_index() == 1);  // the right hand by default

  SECTION("the pointer hand's target is the pixel PointerTarget maps back to it") {
    interfaces::HandTargets targets;
    targets[1] = At(0.15, -0.02, 0.05);
    const auto g = hands.Step(targets, {}, 0.02, 800, 600);
    CHECK(g.pointer_used);
    haptics::PointerState p;
    p.x_px = g.pixel[0];
    p.y_px = g.pixel[1];
    p.width_px = 800;
    p.height_px = 600;
    const auto back = haptics::PointerTarget(p, mouse);
    CHECK(back[0] == Approx(0.15).margin(mouse.metres_per_pixel));
    CHECK(back[1] == Approx(-0.02).margin(mouse.metres_per_pixel));
    CHECK(g.wheel_notches == 0);
    CHECK(g.button);  // nothing to grasp: the button is held to engage
    // Beyond the window: kept at its edge (outside, the hand is let go).
    targets[1] = At(5.0, -5.0, 0.05 + 3 * mouse.wheel_step);
    const auto edge = hands.Step(targets, {}, 0.02, 800, 600);
    CHECK(edge.pixel == std::array<int, 2>{799, 0});
    CHECK(edge.wheel_notches == 3);
  }

  SECTION("the key hand is brought to its target by held keys and stays near it") {
    interfaces::HandTargets targets;
    targets[0] = At(0.05, 0.15, 0.0);  // forward and to the right of rest
    PointerGesture g;
    for (int i = 0; i < 100; ++i) g = hands.Step(targets, {}, 0.02, 800, 600);
    CHECK(hands.key_hand()[0] == Approx(0.05).margin(0.005));
    CHECK(hands.key_hand()[1] == Approx(0.15).margin(0.005));
    CHECK(hands.key_hand()[2] == Approx(0.0).margin(1e-9));
    // Short of it along x: W (+x) held, not S.
    targets[0] = At(0.2, 0.15, 0.0);
    g = hands.Step(targets, {}, 0.02, 800, 600);
    g = hands.Step(targets, {}, 0.02, 800, 600);
    CHECK(g.keys[0]);
    CHECK_FALSE(g.keys[1]);
    // No target: every key released.
    g = hands.Step({}, {}, 0.02, 800, 600);
    for (const bool k : g.keys) CHECK_FALSE(k);
  }

  SECTION("controls to grasp: the button goes down once the fingers are half closed") {
    interfaces::HandTargets neutral;
    neutral[1] = At(0.1, 0.0, 0.05);
    neutral[1]->glove.fill(1.0);
    interfaces::HandTargets open = neutral;
    open[1]->glove.fill(0.2);
    CHECK_FALSE(hands.Step(open, neutral, 0.02, 800, 600).button);
    interfaces::HandTargets closing = neutral;
    closing[1]->glove.fill(0.6);
    CHECK(hands.Step(closing, neutral, 0.02, 800, 600).button);
  }
}

namespace {

/// The cockpit's controls as they rest, for its inverse map (the run reads the real ones).
class RestingControls final : public interfaces::ControlsPort {
 public:
  interfaces::CockpitControls Controls() const override { return {}; }
  void Actuate(const interfaces::ControlActuation&) override {}
};

}  // namespace

TEST_CASE("the pointer pilot brings the open pointer hand round the cockpit's wheel to the lever",
          "[pilot]") {
  const MouseDeviceConfig mouse = LoadDevice(kMouse).mouse;
  const CockpitConfig cockpit = LoadCockpit("config/interfaces/cockpit.yaml");
  RestingControls controls;
  const interfaces::CockpitInterface interface(cockpit, controls);
  const auto lever = interface.HandTargetsFor({})[haptics::Index(haptics::Side::kRight)];
  REQUIRE(lever);
  haptics::Vec3d above_lever = lever->position;
  for (int k = 0; k < 3; ++k) above_lever[k] += lever->approach[k];
  const haptics::Vec3d rest{mouse.centre[0], mouse.centre[1], mouse.centre[2]};
  const testing::PointerApproach approach(rest, above_lever);
  CHECK(approach.At(0.0) == rest);
  CHECK(approach.At(approach.duration_s()) == above_lever);

  // The pointer hand (fingers towards −y, the palm 4 cm either side of the
  // wrist along x, config/physics.yaml) is clear of the rim (a tube of
  // 1.2 cm about the circle in the hub's plane): either wholly behind that
  // plane, or wholly beside the rim, the wrist past its outer edge.
  constexpr double kPalmHalfWidth = 0.04, kRimTube = 0.012;
  auto clear = [&](const haptics::Vec3d& wrist) {
    const bool behind = wrist[0] + kPalmHalfWidth < cockpit.wheel_hub[0] - kRimTube;
    const bool beside = wrist[1] < cockpit.wheel_hub[1] - cockpit.wheel_radius - kRimTube;
    return behind || beside;
  };
  // From where it has been drawn back (at rest its fingers are by the rim).
  const double drawn_back_s =
      PointerApproach::kSettle_s + PointerApproach::kBack_m / PointerApproach::kSpeed_mps;
  CHECK(approach.At(drawn_back_s)[0] == Approx(rest[0] - PointerApproach::kBack_m));
  for (double s = drawn_back_s; s <= approach.duration_s(); s += 0.01) {
    INFO("after " << s << " s");
    CHECK(clear(approach.At(s)));
  }
  // A straight line from the rest catches the rim on its way.
  bool straight_clear = true;
  for (double a = 0.2; a <= 1.0; a += 0.01) {
    haptics::Vec3d p;
    for (int k = 0; k < 3; ++k) p[k] = rest[k] + (above_lever[k] - rest[k]) * a;
    straight_clear = straight_clear && clear(p);
  }
  CHECK_FALSE(straight_clear);
}

/// One lap with `interface`, a run of its own: the pilot drives the whole
/// lap through the pointer, the button and the key hand's keys. Finished,
/// not at the cap.
void DriveALap(const std::string& interface) {
  INFO("interface " << interface);
  XServer x;
  const int domain = test::UniqueDomain(361);
  const std::string vehicle = "mouse-lap";
  const auto dir = test::ScratchDir("e2e-mouse-lap-" + interface);
  // Not quiet: a failure shows the run's progress (engagement, the controls held).
  Child run(MouseRun(interface, domain, vehicle, dir));
  PilotSetup setup;
  setup.domain = domain;
  setup.vehicle_name = vehicle;
  setup.track = kTrack;
  setup.device = kMouse;
  setup.interface = interface;
  PointerPilot pilot(setup);
  pilot.Start();
  // A picture of the hands at work for the docs (build/mouse-screens/),
  // once the pilot has driven a while (after its hands took hold).
  testing::XDesktop desktop;
  bool shot = false;
  // Bounds a hang, asserts no timing: the lap's cap is 60 s of driving.
  test::WaitFor(
      [&] {
        run.Pump();
        if (!shot && pilot.counts().steps > 50 * 10) {
          if (const auto window = desktop.FindWindow("Haptel")) {
            shot = cv::imwrite((ScreensDir() / ("mouse-" + interface + ".png")).string(),
                               desktop.Capture(*window));
          }
        }
        return !run.Alive();
      },
      240.0);
  const int code = run.Wait(10.0);
  pilot.Stop();
  const auto counts = pilot.counts();
  INFO(run.out() << run.err() << "\npilot: states " << counts.states << ", steps " << counts.steps
                 << ", moves " << counts.pointer_moves << ", keys " << counts.key_presses
                 << ", contacts " << counts.contacts << ", regrasps " << counts.regrasps
                 << ", error '" << counts.error << "'");
  // Said on success too: how the pilot got there (a retake costs seconds).
  WARN("pilot (" << interface << "): steps " << counts.steps << ", contacts " << counts.contacts
                 << ", regrasps " << counts.regrasps);
  CHECK(counts.error.empty());
  CHECK(counts.window_found);
  CHECK(counts.pointer_moves > 0);
  REQUIRE(code == 0);
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "completed");
  CHECK(JsonField(json, "device") == "mouse");
  CHECK(std::stod(JsonField(json, "lap_time_s")) < kLapCap_s);
}

// Two cases, so that ctest runs them side by side (tests/e2e/CMakeLists.txt).
TEST_CASE("the pointer pilot drives a lap of the short track with the gesture interfaces",
          "[mouse][laps]") {
  DriveALap(GENERATE(as<std::string>{}, "gesture", "gesture-shared"));
}

// The cockpits: the pointer hand brought round the wheel to the lever
// (PointerApproach), the key hand on the wheel's rim; a ctest entry each
// (tests/e2e/CMakeLists.txt), so that they run side by side.
TEST_CASE("the pointer pilot drives a lap of the short track with the cockpit",
          "[mouse][laps-cockpit]") {
  DriveALap("cockpit");
}

TEST_CASE("the pointer pilot drives a lap of the short track with the assisted cockpit",
          "[mouse][laps-cockpit-assisted]") {
  DriveALap("cockpit-assisted");
}

namespace {

/// The run's window, once up, and the vehicle answering (bounds a wait).
testing::XWindowInfo WindowOf(Child& run, testing::XDesktop& desktop) {
  std::optional<testing::XWindowInfo> window;
  REQUIRE(test::WaitFor(
      [&] {
        run.Pump();
        return (window = desktop.FindWindow("Haptel")).has_value();
      },
      60.0));
  REQUIRE(test::WaitForVehicle(run, 60.0));
  desktop.Focus(*window);
  return *window;
}

}  // namespace

namespace {

/// Draws nothing: the test is about the window's pointer, not its picture.
class EmptyScene final : public view::ViewSource {
 public:
  void Fill(view::ViewModel&) override {}
};

}  // namespace

TEST_CASE("a window that opens under a still pointer has the pointer in it, at its place",
          "[mouse][open]") {
  XServer x;
  // The screen's centre (Xvfb's 1280 x 800): the window opens centred on it.
  testing::XDesktop desktop;
  desktop.MovePointerOnScreen(640, 400);
  interfaces::InputBox box;
  haptics::PointerBox pointer;
  view::SdlInput input(box, pointer);
  EmptyScene scene;
  view::ViewOptions options;
  options.title = "Haptel under a still pointer";
  view::View view(options, scene, &input);
  // No motion is ever sent: the place is the desktop's.
  haptics::PointerState p;
  test::WaitFor(
      [&] {
        p = pointer.Load();
        return p.window_open && p.in_window;
      },
      10.0);
  view.Stop();
  CHECK(p.window_open);
  CHECK(p.in_window);
  CHECK(p.x_px == options.width / 2);
  CHECK(p.y_px == options.height / 2);
}

TEST_CASE("a mouse run with the pointer outside the window moves the vehicle 0 m in 60 s",
          "[mouse][away]") {
  XServer x;
  const int domain = test::UniqueDomain(362);
  const auto dir = test::ScratchDir("e2e-mouse-away");
  Child run(MouseRun("gesture", domain, "mouse-away", dir, {"--time-limit", "60"}));
  testing::XDesktop desktop;
  const testing::XWindowInfo window = WindowOf(run, desktop);
  // Left of and above the window (the screen is larger), the button held and
  // the key hand's forward key too: nobody's hand is in the window.
  desktop.MovePointer(window, -60, -60);
  desktop.Button(1, true);
  desktop.Key(testing::kKeyHandKeysyms[0], true);
  const int code = run.Wait(180.0);
  desktop.Key(testing::kKeyHandKeysyms[0], false);
  desktop.Button(1, false);
  INFO(run.out() << run.err());
  CHECK(code == 1);  // the time limit: no lap
  const std::string json = run.LastLine();
  CHECK(JsonField(json, "outcome") == "time limit");
  CHECK(std::stod(JsonField(json, "distance_m")) == Approx(0.0).margin(1e-3));
  // Disengaged throughout, and counted.
  CHECK(std::stod(JsonField(json, "disengaged_s")) > 50.0);
}

TEST_CASE(
    "screenshots: the hand follows the cursor, and against the gesture's wall after a contact it "
    "is bent away from it",
    "[mouse][screens]") {
  XServer x;
  const int domain = test::UniqueDomain(363);
  const auto dir = test::ScratchDir("e2e-mouse-screens");
  const auto track = testing::WriteObstacleAheadTrack(kTrack, dir);
  const auto trace = dir / "hands.trace";
  std::vector<std::string> argv = MouseRun("gesture", domain, "mouse-screens", dir,
                                           {"--trace", trace.string(), "--time-limit", "90"});
  argv[std::find(argv.begin(), argv.end(), std::string(kTrack)) - argv.begin()] = track.string();
  LinkConfig link = LoadRun("config/haptel.yaml").link;
  link.domain_id = domain;
  testing::RunWatch watch(link, "mouse-screens");
  Child run(argv);
  testing::XDesktop desktop;
  const testing::XWindowInfo window = WindowOf(run, desktop);
  const int cx = window.width_px / 2, cy = window.height_px / 2;
  auto settle = [] { std::this_thread::sleep_for(std::chrono::milliseconds(1500)); };
  auto shot = [&](const std::string& name) {
    CHECK(cv::imwrite((ScreensDir() / (name + ".png")).string(), desktop.Capture(window)));
  };
  // Centre, then 120 px right with the button held: the hand follows (a turn
  // in place, right).
  desktop.MovePointer(window, cx, cy);
  desktop.Button(1, true);
  settle();
  const int64_t centre_ns = MonotonicNs();
  shot("mouse-hand-centre");
  desktop.MovePointer(window, cx + 120, cy);
  settle();
  const int64_t right_ns = MonotonicNs();
  shot("mouse-hand-right");
  // Forward until the bumper touches the obstacle ahead; then pushed 120 px
  // further forward, against the wall.
  watch.Arm();
  desktop.MovePointer(window, cx, cy - 100);
  REQUIRE(test::WaitFor([&] { return watch.contact_ns() != 0; }, 30.0));
  settle();
  const int64_t wall_ns = MonotonicNs();
  shot("mouse-hand-at-wall");
  desktop.MovePointer(window, cx, cy - 220);
  settle();
  const int64_t pushed_ns = MonotonicNs();
  shot("mouse-hand-pushed-into-wall");
  desktop.Button(1, false);
  desktop.Key(XK_Escape, true);
  desktop.Key(XK_Escape, false);
  run.Wait(60.0);
  INFO(run.out() << run.err());
  const std::string json = run.LastLine();
  REQUIRE_FALSE(JsonField(json, "outcome").empty());

  // The device's own account of the hand (its trace), against the cursor's
  // target (PointerTarget: the hand where the pointer alone would put it).
  const MouseDeviceConfig mouse = LoadDevice(kMouse).mouse;
  const auto hand = testing::WristsOf(haptics::ReadTrace(trace), haptics::Side::kRight);
  REQUIRE_FALSE(hand.empty());
  const double m = mouse.metres_per_pixel;
  // Following: 120 px right is 120·m to the device's −y; the centring field
  // holds it back somewhat (pseudo-haptics), never past the cursor.
  const double followed =
      testing::PositionAt(hand, centre_ns)[1] - testing::PositionAt(hand, right_ns)[1];
  CHECK(followed > 0.4 * 120 * m);
  CHECK(followed <= 120 * m + 1e-3);
  // Bent at the wall: the cursor went 120 px further forward, the hand a small part of it.
  const double pushed =
      testing::PositionAt(hand, pushed_ns)[0] - testing::PositionAt(hand, wall_ns)[0];
  CHECK(pushed < 0.3 * 120 * m);
  // The run says it bent the cursor.
  CHECK(std::stod(JsonField(json, "pseudo_haptic_gain_mean")) < 1.0);
}
