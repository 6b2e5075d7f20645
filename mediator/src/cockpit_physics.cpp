#include "haptel/mediator/cockpit_physics.hpp"

namespace haptel::mediator {

interfaces::CockpitControls PhysicsControlsPort::Controls() const {
  const physics::ControlsState s = link_.State();
  return {s.wheel_angle, s.throttle, s.wheel_held, s.throttle_held};
}

void PhysicsControlsPort::Actuate(const interfaces::ControlActuation& a) {
  link_.SetActuation({a.wheel_torque, a.wheel_spring, a.throttle_spring, a.throttle_target, a.throttle_locked});
}

CockpitPhysics::CockpitPhysics(const PhysicsConfig& config, const CockpitConfig& cockpit) {
  world = physics::PhysicsWorld::CreateIfNeeded(config, {.physical_controls = true});
  world->AddHand(haptics::Side::kLeft);
  world->AddHand(haptics::Side::kRight);
  controls = std::make_unique<physics::CockpitControlsBody>(*world, cockpit);
  link = std::make_unique<physics::ControlsLink>(*world, *controls);
  controls->Read();  // gathers the hands' bodies now, not on the physics thread
  port = std::make_unique<PhysicsControlsPort>(*link);
}

CockpitPhysics::~CockpitPhysics() {
  if (world) world->Stop();
}

}  // namespace haptel::mediator
