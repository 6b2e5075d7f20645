// The cockpit interface's hand goals against the real controls: proxy hands
// that follow the goals (as a perfectly tracked operator would) grasp the rim
// and the lever's bar, and moving the goals to an intent moves the controls
// to the positions that express it.
#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/paths.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/mediator/session_physics.hpp"

using namespace haptel;
using haptics::Side;

namespace {

/// The session's cockpit physics, stepped by the test instead of its thread.
struct Cockpit {
  CockpitConfig config = LoadCockpit(ShippedFile("config/interfaces/cockpit.yaml"));
  std::unique_ptr<mediator::SessionPhysics> physics = mediator::SessionPhysics::CreateIfNeeded(
      LoadPhysics(ShippedFile("config/physics.yaml")), {true, true}, &config, nullptr);
  physics::PhysicsWorld& world = *physics->world;
  physics::ControlsLink& link = *physics->link;
  interfaces::CockpitInterface cockpit{config, *physics->port};

  /// `seconds` of steps with the tracked hands on `goals`, shifted by
  /// `lift` along each goal's approach direction (1 = at the approach point).
  void Hold(const interfaces::HandTargets& goals, double seconds, double lift = 0.0,
            double close = 1.0) {
    const int steps = static_cast<int>(seconds / world.config().step_s);
    for (int i = 0; i < steps; ++i) Track(goals, lift, close);
  }
  void Track(const interfaces::HandTargets& goals, double lift, double close) {
    for (int s = 0; s < haptics::kSides; ++s) {
      if (!goals[s]) continue;
      haptics::HandSample sample;
      sample.valid = true;
      for (int k = 0; k < 3; ++k)
        sample.position[k] = goals[s]->position[k] + lift * goals[s]->approach[k];
      sample.orientation = goals[s]->orientation;
      for (int j = 0; j < haptics::kGloveJoints; ++j)
        sample.finger_angles[j] = close * goals[s]->glove[j];
      world.hand(static_cast<Side>(s))->SetTracked(sample);
    }
    world.Step();
  }
  /// The operator's grasp at neutral: down from the approach points with open
  /// hands (0.6 s), fingers closed (0.6 s), held (0.2 s).
  void Grasp() {
    const interfaces::HandTargets neutral = cockpit.HandTargetsFor({});
    for (int i = 0; i <= 300; ++i) Hold(neutral, 0.002, 1.0 - i / 300.0, 0.0);
    for (int i = 0; i <= 300; ++i) Hold(neutral, 0.002, 0.0, i / 300.0);
    Hold(neutral, 0.2);
  }
  /// Moves the goals from one intent to another over `seconds`, like the
  /// operator's arm would.
  void Move(const interfaces::MotionIntent& from, const interfaces::MotionIntent& to,
            double seconds) {
    const int steps = static_cast<int>(seconds / world.config().step_s);
    for (int i = 1; i <= steps; ++i) {
      const double a = static_cast<double>(i) / steps;
      Track(cockpit.HandTargetsFor({from.forward + (to.forward - from.forward) * a,
                                    from.turn + (to.turn - from.turn) * a}),
            0.0, 1.0);
    }
  }
};

}  // namespace

TEST_CASE("cockpit grasp: the operator's hand goals hold the rim and the bar and set them",
          "[physics][cockpit]") {
  Cockpit c;
  const interfaces::HandTargets neutral = c.cockpit.HandTargetsFor({});
  // Open hands above the controls: nothing touched.
  c.Hold(neutral, 0.3, 1.0, 0.0);
  physics::ControlsState s = c.link.State();
  CHECK_FALSE(s.wheel_held);
  CHECK_FALSE(s.throttle_held);
  // Down onto them, open, then closed.
  c.Grasp();
  s = c.link.State();
  INFO("grasped: wheel contacts " << s.wheel_contacts << ", lever contacts "
                                  << s.throttle_contacts);
  CHECK(s.wheel_held);
  CHECK(s.throttle_held);
  CHECK(std::abs(s.wheel_angle) < 0.05);
  CHECK(std::abs(s.throttle) < 0.005);

  // Each intent, reached by moving the hands: the controls follow to the
  // positions the interface's inverse map asks for.
  interfaces::MotionIntent from{};
  for (const interfaces::MotionIntent to :
       {interfaces::MotionIntent{0.9, 0.0}, interfaces::MotionIntent{0.4, 0.35},
        interfaces::MotionIntent{0.4, -0.5}, interfaces::MotionIntent{-0.5, 0.0}}) {
    c.Move(from, to, 1.0);
    c.Hold(c.cockpit.HandTargetsFor(to), 0.3);
    from = to;
    s = c.link.State();
    const interfaces::CockpitControls wanted = c.cockpit.logic().ControlsFor(to);
    INFO("intent forward " << to.forward << " turn " << to.turn << ": wheel " << s.wheel_angle
                           << " (wanted " << wanted.wheel_angle << "), lever " << s.throttle
                           << " (wanted " << wanted.throttle << ")");
    CHECK(s.wheel_angle == Approx(wanted.wheel_angle).margin(0.1));
    CHECK(s.throttle == Approx(wanted.throttle).margin(0.006));
    CHECK(s.wheel_held);
    CHECK(s.throttle_held);
  }
  CHECK(c.world.Counters().hand_resets == 0);
  CHECK(c.physics->controls->resets() == 0);
}

TEST_CASE("cockpit grasp: back and forth, the lever keeps its place in the hand",
          "[physics][cockpit]") {
  Cockpit c;
  c.Grasp();
  interfaces::MotionIntent from{};
  for (int cycle = 0; cycle < 10; ++cycle) {
    for (const interfaces::MotionIntent to :
         {interfaces::MotionIntent{0.9, 0.1}, interfaces::MotionIntent{0.3, -0.2}}) {
      c.Move(from, to, 0.5);
      from = to;
    }
  }
  // Ten round trips of 3.6 cm and 0.39 rad: no ratchet, the grip holds.
  const physics::ControlsState s = c.link.State();
  const interfaces::CockpitControls wanted = c.cockpit.logic().ControlsFor(from);
  INFO("lever " << s.throttle << " (wanted " << wanted.throttle << "), wheel " << s.wheel_angle
                << " (wanted " << wanted.wheel_angle << ")");
  CHECK(s.throttle == Approx(wanted.throttle).margin(0.003));
  CHECK(s.wheel_angle == Approx(wanted.wheel_angle).margin(0.06));
  CHECK(s.throttle_held);
  CHECK(s.wheel_held);
}

TEST_CASE(
    "cockpit grasp: hands that leapt between two steps (a late physics step on a loaded machine) "
    "keep the lever, and bring it after",
    "[physics][cockpit]") {
  Cockpit c;
  c.Grasp();
  // The physics thread held up while the device's hands went on: the next
  // step's hands are the whole way off, the lever's forward (6 cm) then back
  // (12 cm), the wheel's turned half a turn command each way.
  int let_go = 0;
  for (const interfaces::MotionIntent to :
       {interfaces::MotionIntent{1.0, 0.5}, interfaces::MotionIntent{-1.0, -0.5}}) {
    const auto goals = c.cockpit.HandTargetsFor(to);
    for (int i = 0; i < 600; ++i) {
      c.Track(goals, 0.0, 1.0);
      let_go += c.link.State().throttle_held ? 0 : 1;
    }
    const physics::ControlsState s = c.link.State();
    const interfaces::CockpitControls wanted = c.cockpit.logic().ControlsFor(to);
    INFO("lever " << s.throttle << " (wanted " << wanted.throttle << "), steps let go " << let_go);
    CHECK(let_go == 0);
    // Within a slip of the grip (GripGeometry::max_lever_slip): brought, not left behind.
    CHECK(s.throttle == Approx(wanted.throttle).margin(0.015));
    CHECK(s.wheel_held);
  }
  CHECK(c.world.Counters().hand_resets == 0);
}

TEST_CASE(
    "session physics: no world without controls or scene bodies; otherwise only what was asked for",
    "[physics]") {
  const PhysicsConfig config = LoadPhysics(ShippedFile("config/physics.yaml"));
  const uint64_t before = physics::PhysicsWorld::worlds_created();
  CHECK(mediator::SessionPhysics::CreateIfNeeded(config, {false, true}, nullptr, nullptr) ==
        nullptr);
  CHECK(physics::PhysicsWorld::worlds_created() == before);

  // The gesture hand (right only) over a scene: its bodies, one proxy, no controls.
  const Scene scene = LoadSceneFile(ShippedFile("config/scenes/table.xml"));
  const auto p = mediator::SessionPhysics::CreateIfNeeded(config, {false, true}, nullptr, &scene);
  REQUIRE(p);
  CHECK(p->scene.nodes.size() == scene.objects.size());
  CHECK(p->world->hand(Side::kLeft) == nullptr);
  CHECK(p->world->hand(Side::kRight) != nullptr);
  CHECK_FALSE(p->controls);
  CHECK_FALSE(p->port);
}
