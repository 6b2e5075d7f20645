#include "haptel/mediator/session_physics.hpp"

#include <pthread.h>
#include <sched.h>

#include <system_error>
#include <thread>

namespace haptel::mediator {

interfaces::CockpitControls PhysicsControlsPort::Controls() const {
  const physics::ControlsState s = link_.State();
  return {s.wheel_angle, s.throttle, s.wheel_held, s.throttle_held};
}

void PhysicsControlsPort::Actuate(const interfaces::ControlActuation& a) {
  link_.SetActuation({a.wheel_torque, a.wheel_spring, a.throttle_spring, a.throttle_target,
                      a.throttle_locked, a.guidance_active, a.guidance_throttle,
                      a.guidance_wheel_angle, a.guidance_normal_throttle, a.guidance_normal_rim,
                      a.guidance_stiffness, a.guidance_max_force});
}

std::unique_ptr<SessionPhysics> SessionPhysics::CreateIfNeeded(
    const PhysicsConfig& config, const std::array<bool, haptics::kSides>& hands,
    const CockpitConfig* cockpit, const Scene* scene, const std::atomic<bool>* cancel) {
  auto world = physics::PhysicsWorld::CreateIfNeeded(
      config, physics::NeedsOf(scene != nullptr ? *scene : Scene{}, cockpit != nullptr));
  if (!world) return nullptr;
  std::unique_ptr<SessionPhysics> p(new SessionPhysics(std::move(world)));
  for (int s = 0; s < haptics::kSides; ++s) {
    if (hands[s]) p->world->AddHand(static_cast<haptics::Side>(s));
  }
  if (scene != nullptr) p->scene = physics::BuildScene(*p->world, *scene, cancel);
  if (cockpit != nullptr) {
    p->controls = std::make_unique<physics::CockpitControlsBody>(*p->world, *cockpit);
    p->link = std::make_unique<physics::ControlsLink>(*p->world, *p->controls);
    p->controls->Read();  // gathers the hands' bodies now, not on the physics thread
    p->port = std::make_unique<PhysicsControlsPort>(*p->link);
  }
  return p;
}

SessionPhysics::~SessionPhysics() {
  if (!world) return;
  if (!detach_teardown_) {
    world->Stop();
    return;  // the parts go in reverse order: port, link, controls, scene, world
  }
  world->RequestStop();
  // The same parts, in the same order, destroyed on a thread of their own.
  struct Remains {
    std::unique_ptr<physics::PhysicsWorld> world;
    physics::BuiltScene scene;
    std::unique_ptr<physics::CockpitControlsBody> controls;
    std::unique_ptr<physics::ControlsLink> link;
    std::unique_ptr<PhysicsControlsPort> port;
    ~Remains() { world->Stop(); }
  };
  auto remains = std::make_unique<Remains>(std::move(world), std::move(scene), std::move(controls),
                                           std::move(link), std::move(port));
  try {
    std::thread([r = std::move(remains)]() mutable {
      // Only when nothing else wants the processor: the session is recording,
      // the process exiting, and this may take seconds.
      const sched_param idle{};
      pthread_setschedparam(pthread_self(), SCHED_IDLE, &idle);
      r.reset();
    }).detach();
  } catch (const std::system_error&) {
    // No thread to be had: the parts went with the lambda, destroyed here (waiting).
  }
}

}  // namespace haptel::mediator
