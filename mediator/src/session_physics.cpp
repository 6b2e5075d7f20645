#include "haptel/mediator/session_physics.hpp"

namespace haptel::mediator {

interfaces::CockpitControls PhysicsControlsPort::Controls() const {
  const physics::ControlsState s = link_.State();
  return {s.wheel_angle, s.throttle, s.wheel_held, s.throttle_held};
}

void PhysicsControlsPort::Actuate(const interfaces::ControlActuation& a) {
  link_.SetActuation({a.wheel_torque, a.wheel_spring, a.throttle_spring, a.throttle_target, a.throttle_locked});
}

bool SessionPhysics::Needed(const CockpitConfig* cockpit, const Scene* scene) {
  return physics::NeedsWorld(physics::NeedsOf(scene != nullptr ? *scene : Scene{}, cockpit != nullptr));
}

SessionPhysics::SessionPhysics(const PhysicsConfig& config, const std::array<bool, haptics::kSides>& hands,
                               const CockpitConfig* cockpit, const Scene* scene) {
  world = std::make_unique<physics::PhysicsWorld>(config);
  for (int s = 0; s < haptics::kSides; ++s) {
    if (hands[s]) world->AddHand(static_cast<haptics::Side>(s));
  }
  if (scene != nullptr) this->scene = physics::BuildScene(*world, *scene);
  if (cockpit != nullptr) {
    controls = std::make_unique<physics::CockpitControlsBody>(*world, *cockpit);
    link = std::make_unique<physics::ControlsLink>(*world, *controls);
    controls->Read();  // gathers the hands' bodies now, not on the physics thread
    port = std::make_unique<PhysicsControlsPort>(*link);
  }
}

SessionPhysics::~SessionPhysics() {
  if (world) world->Stop();
}

}  // namespace haptel::mediator
