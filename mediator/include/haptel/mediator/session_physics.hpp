#pragma once
/// @file The physics side of a session: a world with the proxy hands the
/// interface uses, the haptic scene's bodies, and for a cockpit the wheel,
/// the lever and the port through which the interface reads and actuates them.
///
/// Physics does not know interfaces and interfaces do not know Bullet; this
/// is the one place that connects the two (and translates their structs).
/// Nothing is built — no world, no thread — when neither the interface nor
/// the scene has bodies (SessionPhysics::Needed).
#include <array>
#include <atomic>
#include <memory>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/config/scene.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/physics/scene_builder.hpp"
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

/// Start the world's thread with `world->Start(hal)`; the destructor stops it
/// before the controls and their link (which the thread uses) go.
struct SessionPhysics {
  std::unique_ptr<physics::PhysicsWorld> world;
  physics::BuiltScene scene;
  /// Set for a cockpit only.
  std::unique_ptr<physics::CockpitControlsBody> controls;
  std::unique_ptr<physics::ControlsLink> link;
  std::unique_ptr<PhysicsControlsPort> port;

  /// The physics side of a session with this cockpit (nullptr: none) and
  /// scene (nullptr: none), or nullptr when neither has bodies — decided by
  /// PhysicsWorld::CreateIfNeeded, like everything else that may need a
  /// world. A proxy hand for each side in `hands`. Throws
  /// std::invalid_argument for a scene the world cannot build. Once
  /// `*cancel` is set the scene's remaining bodies are not built.
  static std::unique_ptr<SessionPhysics> CreateIfNeeded(
      const PhysicsConfig& config, const std::array<bool, haptics::kSides>& hands,
      const CockpitConfig* cockpit, const Scene* scene, const std::atomic<bool>* cancel = nullptr);
  /// From now on the destructor does not wait: it takes the world's forces
  /// out of the HAL (PhysicsWorld::RequestStop) and leaves the rest — a step
  /// still in progress, then removing every body, seconds for thousands of
  /// overlapping ones — to a thread of its own (which a process that exits
  /// meanwhile simply ends). For a session that must record and exit promptly.
  void DetachTeardown() { detach_teardown_ = true; }
  /// Stops the world's thread (waiting for it, unless DetachTeardown), then
  /// destroys the parts.
  ~SessionPhysics();
  SessionPhysics(const SessionPhysics&) = delete;
  SessionPhysics& operator=(const SessionPhysics&) = delete;

 private:
  explicit SessionPhysics(std::unique_ptr<physics::PhysicsWorld> w) : world(std::move(w)) {}
  bool detach_teardown_ = false;
};

}  // namespace haptel::mediator
