#include "haptel/interfaces/cockpit.hpp"

#include <cmath>

namespace haptel::interfaces {

using haptics::Side;
using haptics::Vec3d;

CockpitInterface::CockpitInterface(const CockpitConfig& config, ControlsPort& port,
                                   const GripGeometry& grip)
    : logic_(config), port_(port), grip_(grip) {}

MotorCommand CockpitInterface::Update(double t_s, const VehicleFeedback& feedback, haptics::Hal&) {
  controls_ = port_.Controls();
  port_.Actuate(logic_.Update(t_s, feedback, controls_));
  hud_ = logic_.Hud(feedback, controls_, t_s);
  return logic_.Map(controls_, t_s);
}

HandTargets CockpitInterface::HandTargetsFor(const DriveIntent& intent) const {
  const CockpitConfig& c = logic_.config();
  const CockpitControls wanted = logic_.ControlsFor(intent);
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

}  // namespace haptel::interfaces
