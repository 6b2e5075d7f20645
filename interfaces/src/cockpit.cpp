#include "haptel/interfaces/cockpit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "haptel/interfaces/catalog.hpp"

namespace haptel::interfaces {

using haptics::Side;
using haptics::Vec3d;

CockpitInterface::CockpitInterface(const CockpitConfig& config, ControlsPort& port,
                                   const GripGeometry& grip, const VehicleGeometry& vehicle)
    : logic_(config), port_(port), grip_(grip) {
  if (logic_.config().shared_control.enabled)
    shared_.emplace(logic_.config().shared_control, vehicle);
}

TreadCommand CockpitInterface::Update(double t_s, const VehicleFeedback& feedback,
                                      haptics::Hal& hal) {
  controls_ = port_.Controls();
  // Slip: where each hand is against where its grip on the control would put
  // it. Made up for in HandTargetsFor; forgotten while the control is not held.
  const CockpitConfig& c = logic_.config();
  const double dt = last_update_s_ < 0 ? 0.0 : std::max(0.0, t_s - last_update_s_);
  last_update_s_ = t_s;
  const double a =
      grip_.slip_time_constant > 0 ? 1.0 - std::exp(-dt / grip_.slip_time_constant) : 1.0;
  const haptics::HandSample right = hal.LatestSample(Side::kRight);
  // A locked lever holds against the hand: that is not a slip.
  if (controls_.throttle_held && right.valid && !logic_.throttle_locked(t_s)) {
    const double slip = right.position[0] - (c.throttle_centre[0] + controls_.throttle);
    lever_slip_ +=
        (std::clamp(slip, -grip_.max_lever_slip, grip_.max_lever_slip) - lever_slip_) * a;
  } else if (!controls_.throttle_held) {
    lever_slip_ = 0.0;
  }
  const haptics::HandSample left = hal.LatestSample(Side::kLeft);
  if (controls_.wheel_held && left.valid) {
    const double hand_angle =
        std::atan2(left.position[1] - c.wheel_hub[1], left.position[2] - c.wheel_hub[2]);
    const double slip = std::remainder(hand_angle - controls_.wheel_angle, 2.0 * M_PI);
    wheel_slip_ +=
        (std::clamp(slip, -grip_.max_wheel_slip, grip_.max_wheel_slip) - wheel_slip_) * a;
  } else {
    wheel_slip_ = 0.0;
  }
  actuation_ = logic_.Update(t_s, feedback, controls_);
  if (shared_) {
    // The controls' space: the lever's travel forward, the rim's arc to the
    // left, both in metres, so one stiffness and one bound serve both and the
    // hand feels the same push on either.
    const double r = c.wheel_radius;
    const Vec3d here{controls_.throttle, controls_.wheel_angle * r, 0.0};
    guidance_ = shared_->Guide(echoes_.Filter(feedback.ranges), here, Vec3d{}, [&](const Vec3d& q) {
      CockpitControls at = controls_;
      at.throttle = q[0];
      at.wheel_angle = q[1] / r;
      return logic_.Map(at, t_s);
    });
    const SharedControlConfig& sc = shared_->config();
    actuation_.guidance_active = guidance_.active;
    actuation_.guidance_throttle = guidance_.point[0];
    actuation_.guidance_wheel_angle = guidance_.point[1] / r;
    actuation_.guidance_normal_throttle = guidance_.normal[0];
    actuation_.guidance_normal_rim = guidance_.normal[1];
    actuation_.guidance_stiffness = sc.stiffness;
    actuation_.guidance_max_force = sc.max_force;
  }
  port_.Actuate(actuation_);
  hud_ = logic_.Hud(feedback, controls_, t_s);
  return logic_.Map(controls_, t_s);
}

std::optional<TreadCommand> CockpitInterface::CommandNow(double t_s,
                                                         const haptics::Hal& /*hal*/) const {
  return logic_.Map(port_.Controls(), t_s);
}

HandTargets CockpitInterface::HandTargetsFor(const MotionIntent& intent) const {
  const CockpitConfig& c = logic_.config();
  CockpitControls wanted = logic_.ControlsFor(intent);
  wanted.wheel_angle += wheel_slip_;
  wanted.throttle += lever_slip_;
  std::array<double, haptics::kGloveJoints> closed{};
  // Glove layout (haptics/types.hpp): four thumb joints, then MCP, PIP, DIP
  // of index, middle, ring and pinky. The thumb stays open: over a bar it
  // would only push the fingers' grip sideways.
  for (int f = 0; f < 4; ++f) {
    for (int j = 0; j < 3; ++j) closed[4 + 3 * f + j] = grip_.flexion[j];
  }

  HandTargets targets;
  // Wheel: the grip at the rim's top, turned with the wheel about the hinge
  // axis −x (+ = left): (y, z) → (c·y + s·z, −s·y + c·z) about the hub.
  {
    const double a = wanted.wheel_angle;
    const double ca = std::cos(a), sa = std::sin(a);
    const double y = 0.0, z = c.wheel_radius + grip_.height;
    HandGoal g;
    g.position = {c.wheel_hub[0] - grip_.reach, c.wheel_hub[1] + ca * y + sa * z,
                  c.wheel_hub[2] - sa * y + ca * z};
    g.orientation = {std::cos(0.5 * a), -std::sin(0.5 * a), 0.0, 0.0};
    g.glove = closed;
    // Straight down onto the rim along the turned hand's own −z.
    g.approach = {0.0, sa * grip_.approach, ca * grip_.approach};
    targets[haptics::Index(Side::kLeft)] = g;
  }
  // Throttle: the lever's bar runs along x, the direction it slides, and the
  // hand holds it as the other holds the rim's top: fingers across it (the
  // hand turned −90° about z: fingers to −y, towards the driver's middle),
  // so the grip carries the bar along its own axis, like the rim.
  {
    HandGoal g;
    g.position = {c.throttle_centre[0] + wanted.throttle, c.throttle_centre[1] + grip_.reach,
                  c.throttle_centre[2] + grip_.height};
    g.orientation = {std::sqrt(0.5), 0.0, 0.0, -std::sqrt(0.5)};
    g.glove = closed;
    g.approach = {0.0, 0.0, grip_.approach};
    targets[haptics::Index(Side::kRight)] = g;
  }
  return targets;
}

std::string CockpitInterface::ProgressLine(const TreadCommand& motors) const {
  const CockpitControls& c = controls();
  const HudState& h = hud();
  char hud_text[80] = "";
  if (logic().config().hud) {
    std::snprintf(hud_text, sizeof hud_text, "  HUD %.2f m/s%s%s%s", h.speed,
                  h.turn_left ? " <" : "", h.turn_right ? " >" : "",
                  h.throttle_locked ? " locked" : "");
  }
  char line[260];
  std::snprintf(line, sizeof line,
                "         wheel %+.2f rad%s  throttle %+.3f m%s  motors %+.2f %+.2f%s",
                c.wheel_angle, c.wheel_held ? " (held)" : "", c.throttle,
                c.throttle_held ? " (held)" : "", motors.left, motors.right, hud_text);
  return line;
}

namespace {

// The cockpits in the catalogue (catalog.hpp): their controls are bodies
// the proxy hands move, in a physics world.
const RegisterInterface<RobotFamily, CockpitConfig> kCockpitInterfaces{
    {{.name = "cockpit",
      .family = VehicleFamily::kRobot,
      .hands = {true, true},
      .input = InterfaceInput::kHands,
      .physics = true,
      .summary = "a steering wheel and a throttle lever to grasp"},
     {.name = "cockpit-hud",
      .family = VehicleFamily::kRobot,
      .hands = {true, true},
      .input = InterfaceInput::kHands,
      .physics = true,
      .summary = "the cockpit with a speedometer and turn indicators"},
     {.name = "cockpit-assisted",
      .family = VehicleFamily::kRobot,
      .hands = {true, true},
      .input = InterfaceInput::kHands,
      .physics = true,
      .summary = "the cockpit whose controls return to zero when released"},
     {.name = "cockpit-shared",
      .family = VehicleFamily::kRobot,
      .hands = {true, true},
      .input = InterfaceInput::kHands,
      .physics = true,
      .shared_control = true,
      .summary = "the cockpit with haptic shared control: the wheel and lever pushed away from a "
                 "steer into an obstacle"}},
    LoadCockpit,
    [](const CockpitConfig& config, const InterfaceParts& parts) {
      if (parts.controls == nullptr)
        throw std::invalid_argument("interface '" + config.name + "' needs its controls");
      return std::make_unique<CockpitInterface>(config, *parts.controls, GripGeometry{},
                                                parts.vehicle);
    }};

}  // namespace

}  // namespace haptel::interfaces
