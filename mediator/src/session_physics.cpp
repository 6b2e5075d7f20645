#include "haptel/mediator/session_physics.hpp"

namespace haptel::mediator {

interfaces::CockpitControls PhysicsControlsPort::Controls() const {
  const physics::ControlsState s = link_.State();
  return {s.wheel_angle, s.throttle, s.wheel_held, s.throttle_held};
}

void PhysicsControlsPort::Actuate(const interfaces::ControlActuation& a) {
  link_.SetActuation({a.wheel_torque, a.wheel_spring, a.throttle_spring, a.throttle_target, a.throttle_locked});
}

std::unique_ptr<SessionPhysics> SessionPhysics::CreateIfNeeded(const PhysicsConfig& config,
                                                               const std::array<bool, haptics::kSides>& hands,
                                                               const CockpitConfig* cockpit, const Scene* scene) {
  auto world = physics::PhysicsWorld::CreateIfNeeded(
      config, physics::NeedsOf(scene != nullptr ? *scene : Scene{}, cockpit != nullptr));
  if (!world) return nullptr;
  std::unique_ptr<SessionPhysics> p(new SessionPhysics(std::move(world)));
  for (int s = 0; s < haptics::kSides; ++s) {
    if (hands[s]) p->world->AddHand(static_cast<haptics::Side>(s));
  }
  if (scene != nullptr) p->scene = physics::BuildScene(*p->world, *scene);
  if (cockpit != nullptr) {
    p->controls = std::make_unique<physics::CockpitControlsBody>(*p->world, *cockpit);
    p->link = std::make_unique<physics::ControlsLink>(*p->world, *p->controls);
    p->controls->Read();  // gathers the hands' bodies now, not on the physics thread
    p->port = std::make_unique<PhysicsControlsPort>(*p->link);
  }
  return p;
}

SessionPhysics::~SessionPhysics() {
  if (world) world->Stop();
}

}  // namespace haptel::mediator
