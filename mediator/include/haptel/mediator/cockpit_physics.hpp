#pragma once
/// @file The physics side of a cockpit session: a world with both proxy
/// hands, the wheel and the lever, and the port through which the cockpit
/// interface reads and actuates them.
///
/// Physics does not know interfaces and interfaces do not know Bullet; this
/// is the one place that connects the two (and translates their structs).
#include <memory>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/physics/world.hpp"

namespace haptel::mediator {

/// The cockpit interface's view of the controls in a physics world. Any thread.
class PhysicsControlsPort final : public interfaces::ControlsPort {
 public:
  explicit PhysicsControlsPort(physics::ControlsLink& link) : link_(link) {}
  interfaces::CockpitControls Controls() const override;
  void Actuate(const interfaces::ControlActuation& actuation) override;

 private:
  physics::ControlsLink& link_;
};

/// Builds the world, hands, controls and port. Start the world's thread with
/// `world->Start(hal)`; the destructor stops it before the controls and their
/// link (which the thread uses) go.
struct CockpitPhysics {
  std::unique_ptr<physics::PhysicsWorld> world;
  std::unique_ptr<physics::CockpitControlsBody> controls;
  std::unique_ptr<physics::ControlsLink> link;
  std::unique_ptr<PhysicsControlsPort> port;

  CockpitPhysics(const PhysicsConfig& config, const CockpitConfig& cockpit);
  ~CockpitPhysics();
  CockpitPhysics(const CockpitPhysics&) = delete;
  CockpitPhysics& operator=(const CockpitPhysics&) = delete;
};

}  // namespace haptel::mediator
