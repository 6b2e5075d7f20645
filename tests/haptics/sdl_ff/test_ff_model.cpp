// The sdl-ff device's pure parts: axes to hands (against the cockpit's own
// grips), the deadman, the effects for a field, a wall and a shake, their
// clamping, and what SDL is handed for them.
#include <catch2/catch.hpp>
#include <cmath>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/error.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/sdl_ff/ff_model.hpp"
#include "haptel/sdl_ff/sdl_effects.hpp"
#include "test_env.hpp"

using namespace haptel;
using namespace haptel::haptics;
using namespace haptel::haptics::sdl_ff;

namespace {

/// The shipped joystick's right hand: stick y → hand x, stick x → hand y, 0.1 m.
SdlFfDeviceConfig Stick() { return LoadDevice("config/devices/sdl-ff.yaml").sdl_ff; }
SdlFfDeviceConfig Wheel() { return LoadDevice("config/devices/sdl-ff-wheel.yaml").sdl_ff; }

Axes At(std::initializer_list<std::pair<int, double>> values) {
  Axes axes{};
  for (const auto& [i, v] : values) axes[static_cast<size_t>(i)] = v;
  return axes;
}

/// The gesture's field: 40 N/m to the neutral, and a wall when asked.
ForceField Field(const Vec3d& neutral = {}) {
  ForceField f;
  f.enabled = true;
  f.neutral = neutral;
  f.stiffness = 40.0;
  return f;
}

std::array<FfSide, kSides> RightOnly(const ForceField& field, const Vec3d& force) {
  std::array<FfSide, kSides> sides{};
  sides[1] = FfSide{.used = true, .fresh = true, .field = field, .force = force};
  return sides;
}

class FixedControls final : public interfaces::ControlsPort {
 public:
  interfaces::CockpitControls Controls() const override { return {}; }
  void Actuate(const interfaces::ControlActuation&) override {}
};

}  // namespace

TEST_CASE("sdl-ff: SDL's axis values are normalised to [-1, 1]") {
  CHECK(AxisFromSdl(0) == 0.0);
  CHECK(AxisFromSdl(32767) == 1.0);
  CHECK(AxisFromSdl(-32768) == -1.0);
  CHECK(AxisFromSdl(-16384) == Approx(-0.5).margin(1e-4));
}

TEST_CASE("sdl-ff: a stick moves the gesture hand around its neutral, a pedal from its rest") {
  const SdlFfDeviceConfig stick = Stick();
  // Stick half forward (y reads negative) and a quarter right (x positive).
  const HandPose pose = HandFromAxes(stick.right, At({{1, -0.5}, {0, 0.25}}));
  CHECK(pose.position[0] == Approx(0.05));    // forward
  CHECK(pose.position[1] == Approx(-0.025));  // to the right is −y
  CHECK(pose.position[2] == 0.0);
  CHECK(HandFromAxes(stick.right, At({})).position == Vec3d{0.0, 0.0, 0.0});

  // The wheel's lever: accelerator (axis 2) and brake (axis 3) both rest high.
  const SdlFfDeviceConfig wheel = Wheel();
  const double released = 1.0;
  CHECK(HandFromAxes(wheel.right, At({{2, released}, {3, released}})).position[0] == Approx(0.05));
  CHECK(HandFromAxes(wheel.right, At({{2, -1.0}, {3, released}})).position[0] == Approx(0.11));
  CHECK(HandFromAxes(wheel.right, At({{2, 0.0}, {3, released}})).position[0] == Approx(0.08));
  CHECK(HandFromAxes(wheel.right, At({{2, released}, {3, -1.0}})).position[0] == Approx(-0.01));
}

TEST_CASE("sdl-ff: the wheel's hands sit on the cockpit's grips and turn with the rim") {
  const SdlFfDeviceConfig wheel = Wheel();
  CockpitConfig cockpit = LoadCockpit("config/interfaces/cockpit-assisted.yaml");
  FixedControls controls;
  const interfaces::CockpitInterface face(cockpit, controls);
  const interfaces::HandTargets grips = face.HandTargetsFor({});
  // Wheel straight, lever at its centre (pedals released): the cockpit's grips.
  const Axes rest = At({{0, 0.0}, {2, 1.0}, {3, 1.0}});
  for (const Side side : {Side::kLeft, Side::kRight}) {
    INFO("side " << Index(side));
    const HandPose pose = HandFromAxes(side == Side::kLeft ? wheel.left : wheel.right, rest);
    const interfaces::HandGoal& grip = *grips[static_cast<size_t>(Index(side))];
    for (int i = 0; i < 3; ++i) CHECK(pose.position[i] == Approx(grip.position[i]).margin(1e-9));
    for (int i = 0; i < 4; ++i)
      CHECK(pose.orientation[i] == Approx(grip.orientation[i]).margin(1e-9));
  }
  // Turned fully right: −135° about −x, as the cockpit turns its grip.
  const double a = -135.0 * M_PI / 180.0;
  const HandPose turned = HandFromAxes(wheel.left, At({{0, 1.0}}));
  CHECK(turned.position[0] == Approx(-0.065));
  CHECK(turned.position[1] == Approx(0.143 * std::sin(a)));
  CHECK(turned.position[2] == Approx(0.143 * std::cos(a)));
  CHECK(turned.orientation[0] == Approx(std::cos(0.5 * a)));
  CHECK(turned.orientation[1] == Approx(-std::sin(0.5 * a)));
}

TEST_CASE("sdl-ff: a hand's lever on an axis is the derivative of its position") {
  const SdlFfDeviceConfig wheel = Wheel();
  const Axes at = At({{0, 0.3}, {2, 0.2}, {3, 0.6}});
  const double h = 1e-6;
  for (const auto& [hand, axis] :
       {std::pair{&wheel.left, 0}, std::pair{&wheel.right, 2}, std::pair{&wheel.right, 3}}) {
    Axes up = at, down = at;
    up[static_cast<size_t>(axis)] += h;
    down[static_cast<size_t>(axis)] -= h;
    const Vec3d lever = HandLever(*hand, at, axis);
    for (int i = 0; i < 3; ++i) {
      const double numeric =
          (HandFromAxes(*hand, up).position[i] - HandFromAxes(*hand, down).position[i]) / (2 * h);
      CHECK(lever[i] == Approx(numeric).margin(1e-6));
    }
  }
  CHECK(HandLever(wheel.left, at, 2) == Vec3d{0.0, 0.0, 0.0});  // not moved by it
}

TEST_CASE("sdl-ff: the deadman is its button, or its trigger past the threshold") {
  SdlFfDeadman button;  // button 0
  CHECK(DeadmanHeld(button, {}, 0b1));
  CHECK_FALSE(DeadmanHeld(button, {}, 0b10));
  SdlFfDeadman trigger{.button = -1, .axis = 5, .rest_high = false, .threshold = 0.5};
  CHECK_FALSE(DeadmanHeld(trigger, At({{5, -1.0}}), 0b1));  // released: at its low rest
  CHECK_FALSE(DeadmanHeld(trigger, At({{5, -0.1}}), 0));    // 45 % of its travel
  CHECK(DeadmanHeld(trigger, At({{5, 0.1}}), 0));           // 55 %
  trigger.rest_high = true;
  CHECK(DeadmanHeld(trigger, At({{5, -0.1}}), 0));
  // The hands close on the cockpit's grip while it is held.
  const auto closed = GlovePosture({0.2, 1.6, 1.4}, true);
  CHECK(closed[4] == 0.2);
  CHECK(closed[5] == 1.6);
  CHECK(closed[15] == 1.4);
  CHECK(closed[0] == 0.0);  // the thumb stays open
  CHECK(GlovePosture({0.2, 1.6, 1.4}, false) == std::array<double, kGloveJoints>{});
}

TEST_CASE("sdl-ff: the gesture's field plays as the stick's spring, the rest as constant force") {
  const SdlFfDeviceConfig stick = Stick();
  const double limit = 7.0;
  SECTION("the spring: centre at the neutral, coefficient k·span over the limit") {
    const FfPlan plan =
        PlanEffects(stick, RightOnly(Field({0.02, -0.01, 0.0}), {}), At({}), 2, true, limit);
    REQUIRE(plan.spring[0].active);
    REQUIRE(plan.spring[1].active);
    CHECK_FALSE(plan.spring[2].active);
    CHECK(plan.spring[1].centre == Approx(-0.2));  // x = 0.02 m: stick 20 % forward
    CHECK(plan.spring[0].centre == Approx(0.1));   // y = −0.01 m: stick 10 % right
    CHECK(plan.spring[1].coefficient == Approx(40.0 * 0.1 / 7.0));
  }
  SECTION("the spring renders the field's stiffness: the constant adds only what it does not") {
    // Hand 5 cm forward: the field pulls back 2 N, which the spring plays itself.
    const Axes axes = At({{1, -0.5}});
    FfPlan plan = PlanEffects(stick, RightOnly(Field(), {-2.0, 0.0, 0.0}), axes, 2, true, limit);
    CHECK(plan.constant[1] == Approx(0.0).margin(1e-9));
    CHECK(plan.constant[0] == Approx(0.0).margin(1e-9));
    // One newton more backwards (a wall): the stick pushed back (its y value up) by 1 N of 7.
    plan = PlanEffects(stick, RightOnly(Field(), {-3.0, 0.0, 0.0}), axes, 2, true, limit);
    CHECK(plan.constant[1] == Approx(1.0 / 7.0));
    // A device without a spring plays the whole force as constant force.
    plan = PlanEffects(stick, RightOnly(Field(), {-2.0, 0.0, 0.0}), axes, 2, false, limit);
    CHECK_FALSE(plan.spring[1].active);
    CHECK(plan.constant[1] == Approx(2.0 / 7.0));
    // A force to the left (+y) pushes the stick left: its x value down.
    plan = PlanEffects(stick, RightOnly(Field(), {0.0, 0.7, 0.0}), At({}), 2, true, limit);
    CHECK(plan.constant[0] == Approx(-0.1));
  }
  SECTION("clamped: a spring stiffer than the device, a force beyond its limit") {
    ForceField stiff = Field({0.5, 0.0, 0.0});  // a neutral beyond the stick's reach
    stiff.stiffness = 1000.0;
    const FfPlan plan =
        PlanEffects(stick, RightOnly(stiff, {-30.0, 0.0, 0.0}), At({{1, -1.0}}), 2, true, limit);
    CHECK(plan.spring[1].coefficient == 1.0);
    CHECK(plan.spring[1].centre == -1.0);
    CHECK(plan.constant[1] == 1.0);
  }
  SECTION("nothing plays from a stale set-point or a side the device lacks") {
    std::array<FfSide, kSides> sides = RightOnly(Field(), {-3.0, 0.0, 0.0});
    sides[1].fresh = false;
    FfPlan plan = PlanEffects(stick, sides, At({{1, -0.5}}), 2, true, limit);
    CHECK_FALSE(plan.spring[1].active);
    CHECK(plan.constant[1] == 0.0);
    sides[1].fresh = true;
    sides[1].used = false;
    plan = PlanEffects(stick, sides, At({{1, -0.5}}), 2, true, limit);
    CHECK(plan.constant[1] == 0.0);
  }
}

TEST_CASE("sdl-ff: a wall pressed is measured for rumble; the wheel's coupling turns the wheel") {
  const SdlFfDeviceConfig stick = Stick();
  ForceField walled = Field();
  walled.wall_active = true;
  walled.wall_point = {0.03, 0.0, 0.0};
  walled.wall_normal = {1.0, 0.0, 0.0};
  walled.wall_stiffness = 1500.0;
  // 2 mm into the wall: 3 N of 7.
  FfPlan plan = PlanEffects(stick, RightOnly(walled, {}), At({{1, -0.32}}), 0, false, 7.0);
  CHECK(plan.wall_press == Approx(3.0 / 7.0));
  plan = PlanEffects(stick, RightOnly(walled, {}), At({{1, -0.2}}), 0, false, 7.0);
  CHECK(plan.wall_press == 0.0);  // in front of it
  walled.wall_stiffness = 1e5;
  plan = PlanEffects(stick, RightOnly(walled, {}), At({{1, -0.32}}), 0, false, 7.0);
  CHECK(plan.wall_press == 1.0);

  // The wheel: a force along the rim's tangent at the top (+y, to the left)
  // turns the wheel left: its axis value down (right is +).
  const SdlFfDeviceConfig wheel = Wheel();
  std::array<FfSide, kSides> sides{};
  sides[0] = FfSide{.used = true, .fresh = true, .field = {}, .force = {0.0, 1.4, 0.0}};
  plan = PlanEffects(wheel, sides, At({{2, 1.0}, {3, 1.0}}), 1, true, 7.0);
  CHECK_FALSE(plan.spring[0].active);  // the cockpit has no field: its springs are the coupling's
  CHECK(plan.constant[0] == Approx(-0.2));
}

TEST_CASE("sdl-ff: a contact of the vehicle shakes once, not while shaking; forces never do") {
  SdlFfDeviceConfig config = Stick();  // 0.3 s
  ShakeTrigger shake(config);
  std::array<FfSide, kSides> sides = RightOnly(Field(), {});
  CHECK_FALSE(shake.Step(0.00, sides));
  sides[1].force = {-5.0, 0.0, 0.0};  // a driven control's force stepping: no contact
  CHECK_FALSE(shake.Step(0.01, sides));
  sides[1].field.wall_active = true;  // the gesture's wall alone is no contact
  CHECK_FALSE(shake.Step(0.02, sides));
  sides[1].contacts = 1;  // the bumper closed
  CHECK(shake.Step(0.03, sides));
  CHECK_FALSE(shake.Step(0.04, sides));  // the same contact: once
  sides[1].contacts = 2;
  CHECK_FALSE(shake.Step(0.05, sides));  // still shaking: it plays on
  CHECK_FALSE(shake.Step(0.40, sides));  // that contact was seen: no late shake
  sides[1].contacts = 3;
  CHECK(shake.Step(0.41, sides));
  sides[0].contacts = 9;  // a side the device lacks counts nothing
  CHECK_FALSE(shake.Step(0.80, sides));
}

TEST_CASE("sdl-ff: SDL's effects: spring axes, constant force's direction and level, the sine") {
  std::array<SpringAxis, kFfAxes> springs{};
  springs[1] = {.active = true, .centre = -0.2, .coefficient = 0.5};
  const SDL_HapticEffect spring = SpringEffect(springs);
  CHECK(spring.type == SDL_HAPTIC_SPRING);
  CHECK(spring.condition.length == SDL_HAPTIC_INFINITY);
  CHECK(spring.condition.center[1] == -6553);
  CHECK(spring.condition.right_coeff[1] == 16384);
  CHECK(spring.condition.left_coeff[1] == 16384);
  CHECK(spring.condition.right_sat[1] == 0xFFFF);
  CHECK(spring.condition.right_coeff[0] == 0);  // inactive: no spring on x

  // Pushing the stick's y value up (towards the user): the force comes from −y.
  SDL_HapticEffect constant = ConstantEffect({0.0, 0.25, 0.0});
  CHECK(constant.type == SDL_HAPTIC_CONSTANT);
  CHECK(constant.constant.direction.type == SDL_HAPTIC_CARTESIAN);
  CHECK(constant.constant.direction.dir[0] == 0);
  CHECK(constant.constant.direction.dir[1] < 0);
  CHECK(constant.constant.level == 8192);
  constant = ConstantEffect({0.9, -0.9, 0.0});  // beyond full together: clamped
  CHECK(constant.constant.level == 32767);
  CHECK(constant.constant.direction.dir[0] < 0);
  CHECK(constant.constant.direction.dir[1] > 0);

  SdlFfDeviceConfig config;
  config.shake_hz = 12.0;
  config.shake_level = 0.6;
  config.shake_s = 0.3;
  const SDL_HapticEffect sine = ShakeEffect(config);
  CHECK(sine.type == SDL_HAPTIC_SINE);
  CHECK(sine.periodic.period == 83);
  CHECK(sine.periodic.magnitude == 19660);
  CHECK(sine.periodic.length == 300);
  CHECK(RumbleLevel(0.5) == 32768);
  CHECK(RumbleLevel(2.0) == 65535);
  CHECK(RumbleLevel(-1.0) == 0);
}

TEST_CASE("sdl-ff: a device file's sdl_ff section is checked, naming the key") {
  const auto dir = haptel::test::ScratchDir("sdl-ff-config");
  const auto load = [&](const std::string& section) {
    return LoadDevice(haptel::test::WriteFile(
        dir / "stick.yaml", "name: stick\ndriver: sdl-ff\nsides: [right]\nsdl_ff:\n" + section));
  };
  CHECK(load("  deadman: {button: -1, axis: 5, rest: high}\n").sdl_ff.deadman.rest_high);
  CHECK_THROWS_WITH(load("  deadman: {button: 1, axis: 5}\n"),
                    Catch::Contains("sdl_ff.deadman.button") &&
                        Catch::Contains("exactly one of 'button' and 'axis'"));
  CHECK_THROWS_WITH(load("  deadman: {button: -1}\n"), Catch::Contains("sdl_ff.deadman.button"));
  CHECK_THROWS_WITH(
      load("  right: {rim: {axis: 0}, y: {axis: 1, span: 0.1}}\n"),
      Catch::Contains("sdl_ff.right.rim.axis") && Catch::Contains("a rim moves y and z"));
  CHECK_THROWS_WITH(load("  right: {x: {axis: 1, span: 0.1, rest: middle}}\n"),
                    Catch::Contains("sdl_ff.right.x.rest") && Catch::Contains("centre, low, high"));
  CHECK_THROWS_WITH(load("  right: {x: {axis: 64}}\n"), Catch::Contains("sdl_ff.right.x.axis"));
  CHECK_THROWS_WITH(load("  stick: 1\n"), Catch::Contains("stick"));  // unknown keys refused
}
