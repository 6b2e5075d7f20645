#pragma once
/// @file The physics world: Bullet in double precision, stepped at a fixed
/// step on its own thread, with the proxy hands and the scene's bodies.
///
/// Each physics tick reads the calibrated hands from the HAL
/// (Hal::LatestSample), moves the proxy hands' targets, steps once, and writes
/// each side's set-point (read-modify-write: the interface's force field and
/// any other field are kept) with the proxy coupling and the finger forces.
/// The servo loop renders k·(proxy − tracked) at 1 kHz from the latest
/// set-point; it never waits for this thread.
///
/// A body whose pose or velocity turns NaN or infinite is put back (a hand on
/// the tracked hand, a scene body where it was created), counted, and the
/// world goes on.
///
/// Threading: set the scene up (Add*) before Start; while the thread runs,
/// only Counters, Stats, Poses, running, RequestStop and Stop may be called
/// from other threads. Without Start, Step and Tick drive the world
/// deterministically.
///
/// Sleeping bodies cost nothing (DESIGN.md): a scene body that Bullet has put
/// to sleep is *parked* — taken out of the Bullet world, so that none of its
/// per-step loops (islands, activation, integration, pairs) visits it — and
/// kept in a bounding-box tree of its own. Before every step, each awake body
/// of the world (hands, controls, awake scene bodies) asks that tree with its
/// bounding box, grown by how far it can move in two steps: a parked body it
/// could touch is put back into the world, awake, with everything parked
/// that touches it, before the step that could bring them into contact. A
/// parked body keeps its pose (BodyPose, ObjectPose), its zero velocity, its
/// material, its gravity and its collision filter. Counters tell how many
/// are parked and awake.
///
/// Stopping never waits for a step: RequestStop takes the world's forces out
/// of the HAL at once and cuts the step in progress short (between contact
/// pairs, manifolds and solver iterations); Stop(timeout) bounds the wait
/// for the thread.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "haptel/config/physics.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/physics/proxy_hand.hpp"

class btCollisionObject;
class btCollisionShape;
class btDiscreteDynamicsWorld;
class btRigidBody;

namespace haptel {
class PeriodicThread;
}

namespace haptel::physics {

/// What a scene and its interface ask of physics. DESIGN.md: no physics world
/// when the interface has no physical controls and the scene no bodies (the
/// hands alone have nothing to touch: the tracked hand is drawn as is).
struct PhysicsNeeds {
  bool physical_controls = false;  ///< e.g. a steering wheel and throttle the hands grab
  int scene_bodies = 0;            ///< touchable bodies in the haptic scene
};
/// Cheap: decides without creating anything.
constexpr bool NeedsWorld(const PhysicsNeeds& needs) {
  return needs.physical_controls || needs.scene_bodies > 0;
}

/// Events the physics thread counts instead of logging.
struct PhysicsCounters {
  uint64_t steps = 0;
  uint64_t hand_resets = 0;      ///< hands reset to the tracked pose after a NaN/Inf body
  uint64_t body_resets = 0;      ///< scene bodies put back after a NaN/Inf
  uint64_t invalid_samples = 0;  ///< side-ticks without a valid, finite tracked hand
  uint64_t setpoints = 0;        ///< set-points written to the HAL
  double last_step_us = 0.0;     ///< compute time of the latest step
  double max_step_us = 0.0;
  /// Dynamic scene bodies after the latest step: asleep and out of the Bullet
  /// world (parked), and awake in it. The rest are asleep in the world (near
  /// an awake body, about to be parked) or static.
  uint64_t parked_bodies = 0;
  uint64_t awake_bodies = 0;
  uint64_t parkings = 0;  ///< bodies parked so far
  uint64_t wakings = 0;   ///< parked bodies put back into the world so far
};

/// Index of a scene body in its world.
using BodyId = int;

/// Work that must run on the stepping thread around every step, such as the
/// cockpit controls trading their state for the interface's actuation. It
/// runs inside the physics loop: no allocation, no blocking, no logging.
class StepHook {
 public:
  virtual ~StepHook() = default;
  virtual void BeforeStep() {}
  virtual void AfterStep() {}
};

class PhysicsWorld {
 public:
  /// Validates `config` first (PhysicsConfig::ValidateOrThrow: ConfigFieldError).
  explicit PhysicsWorld(const PhysicsConfig& config);
  ~PhysicsWorld();
  PhysicsWorld(const PhysicsWorld&) = delete;
  PhysicsWorld& operator=(const PhysicsWorld&) = delete;

  /// A world only when `needs` calls for one; nullptr otherwise.
  static std::unique_ptr<PhysicsWorld> CreateIfNeeded(const PhysicsConfig& config,
                                                      const PhysicsNeeds& needs);
  /// Worlds constructed in this process so far.
  static uint64_t worlds_created();

  // --- Scene set-up: before Start. Static bodies never move; dynamic ones
  // may fall asleep when at rest and cost nothing until touched. ---
  /// The half-space below the plane n·x = offset (n points out of it).
  BodyId AddStaticPlane(const Vec3d& normal, double offset, const PhysicsMaterial& material = {});
  BodyId AddStaticBox(const Vec3d& center, const Vec3d& half_extents,
                      const PhysicsMaterial& material = {});
  BodyId AddDynamicBox(const Vec3d& center, const Vec3d& half_extents, double mass,
                       const PhysicsMaterial& material = {});
  BodyId AddDynamicSphere(const Vec3d& center, double radius, double mass,
                          const PhysicsMaterial& material = {});
  /// A body of any Bullet shape (for scene builders, see scene_builder.hpp).
  /// The world owns `shape` and `parts` (the children a compound `shape`
  /// refers to). `pose` places the body frame — for a dynamic body at its
  /// centre of mass along its principal axes; mass 0 makes the body static;
  /// `principal_inertia` (kg·m², body frame) is ignored when static.
  BodyId AddRigidBody(std::unique_ptr<btCollisionShape> shape,
                      std::vector<std::unique_ptr<btCollisionShape>> parts, double mass,
                      const Vec3d& principal_inertia, const Pose& pose,
                      const PhysicsMaterial& material = {});
  /// The proxy hand of `side` (one per side; a second call returns the first).
  ProxyHand& AddHand(Side side);
  ProxyHand* hand(Side side) { return hands_[haptics::Index(side)].get(); }
  /// Runs `hook` around every Step, in the order added. Before Start; the
  /// hook must outlive the world (or at least its Stop).
  void AddStepHook(StepHook& hook) { hooks_.push_back(&hook); }

  Pose BodyPose(BodyId id) const;
  Vec3d BodyVelocity(BodyId id) const;
  /// True while the body is asleep, parked or not.
  bool BodySleeping(BodyId id) const;
  /// True while the body is asleep and out of the Bullet world (see the top).
  bool BodyParked(BodyId id) const;
  /// The Bullet body, to read or change. A parked body is first put back
  /// into the world as it was (asleep), so that whatever the caller does to
  /// it acts as it would have; a step parks it again if it is still asleep.
  /// A reference kept from earlier does not do this: call body() again.
  btRigidBody& body(BodyId id);
  /// Reading only: a parked body stays parked.
  const btRigidBody& body(BodyId id) const;
  /// Parking is on from the start; off puts every parked body back into the
  /// world (asleep) and keeps sleeping bodies there, as plain Bullet does.
  /// Before Start.
  void SetParking(bool on);
  bool parking() const { return parking_; }

  /// One fixed step of config().step_s, then the NaN/Inf check.
  void Step();
  /// One physics-thread cycle at `now_ns`: tracked hands from `hal`, one step,
  /// set-points to `hal`.
  void Tick(haptics::Hal& hal, int64_t now_ns);
  /// Runs Tick on a thread of its own at 1/step_s. `hal` must outlive
  /// RequestStop (the thread uses it until then, and never after).
  void Start(haptics::Hal& hal);
  /// Ends the thread's use of the HAL and turns the proxy coupling and finger
  /// forces off there (keeping the interface's field) at once, and cuts the
  /// step in progress short; does not wait for the thread to end (a single
  /// step of thousands of overlapping bodies can take minutes). Returns within
  /// microseconds. Safe to call twice.
  void RequestStop();
  /// RequestStop, then waits at most `timeout_s` for the thread to end: true
  /// when it has (joined), false when it is still finishing its step — it
  /// ends by itself; the world must not be destroyed before (the destructor
  /// waits for it).
  bool Stop(double timeout_s);
  /// RequestStop, then waits for the thread to end. Safe to call twice.
  void Stop();
  bool running() const { return running_.load(); }

  /// Safe from any thread.
  PhysicsCounters Counters() const { return published_counters_.Load(); }
  /// The thread's rate and period statistics (zero before Start).
  LoopStats Stats() const;
  /// The latest poses of a side's hands (valid = false when there is no hand). Any thread.
  HandPoses Poses(Side side) const { return poses_[haptics::Index(side)].Load(); }

  const PhysicsConfig& config() const { return config_; }
  btDiscreteDynamicsWorld& bullet();

 private:
  struct Body;
  struct Reach;
  struct Bullet;
  BodyId AddBody(std::unique_ptr<Body> body);
  void CheckFinite();
  /// Before a step: each awake body's reach (Bullet::movers), and the parked
  /// bodies inside one, with the parked bodies touching those, put back awake.
  void WakeParked();
  /// After a step: sleeping scene bodies out of every mover's reach leave
  /// the world; counts parked and awake bodies.
  void ParkSleeping();
  /// Puts a parked body back into the world, as it was (asleep).
  void Unpark(Body& body);
  /// Ours when `object` is one of the scene's bodies, else nullptr.
  Body* SceneBody(const btCollisionObject& object);
  /// Drops every overlapping pair in one pass (see the destructor).
  void ForgetAllPairs();
  /// The stepping thread's use of the HAL: EnterHal is false once a stop is
  /// requested, and RequestStop waits for the uses in progress to leave.
  bool EnterHal();
  void LeaveHal();

  PhysicsConfig config_;
  /// Set by RequestStop: the thread ends after its tick, the step in
  /// progress gives up. Before bullet_, which watches it.
  std::atomic<bool> stop_requested_{false};
  std::atomic<int> hal_users_{0};
  std::unique_ptr<Bullet> bullet_;
  std::vector<std::unique_ptr<Body>> bodies_;
  std::array<std::unique_ptr<ProxyHand>, haptics::kSides> hands_;
  std::vector<StepHook*> hooks_;
  bool parking_ = true;
  uint64_t parked_count_ = 0;
  std::array<bool, haptics::kSides> tracked_ok_{};  ///< this tick's sample was usable
  PhysicsCounters counters_;                        ///< the stepping thread's own copy
  Seqlock<PhysicsCounters> published_counters_;
  std::array<Seqlock<HandPoses>, haptics::kSides> poses_;
  std::unique_ptr<PeriodicThread> thread_;
  haptics::Hal* hal_ = nullptr;
  std::atomic<bool> running_{false};
  int64_t last_tick_ns_ = 0;
};

}  // namespace haptel::physics
