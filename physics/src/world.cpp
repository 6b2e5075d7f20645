#include "haptel/physics/world.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <thread>

#include "bullet_util.hpp"
#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/periodic_thread.hpp"

namespace haptel::physics {
namespace {

std::atomic<uint64_t> g_worlds_created{0};

// DESIGN.md: material pairs combine by the average (Bullet's default is the
// product). Bullet reads these process-wide hooks when a contact is created.
btScalar AverageFriction(const btCollisionObject* a, const btCollisionObject* b) {
  return 0.5 * (a->getFriction() + b->getFriction());
}
btScalar AverageRestitution(const btCollisionObject* a, const btCollisionObject* b) {
  return 0.5 * (a->getRestitution() + b->getRestitution());
}
// Rolling and spinning friction are lever arms that add up (PhysicsMaterial);
// Bullet's default weighs each by the other body's friction coefficient.
btScalar SumRollingFriction(const btCollisionObject* a, const btCollisionObject* b) {
  return a->getRollingFriction() + b->getRollingFriction();
}
btScalar SumSpinningFriction(const btCollisionObject* a, const btCollisionObject* b) {
  return a->getSpinningFriction() + b->getSpinningFriction();
}

/// m: an awake body reaches this much farther than two steps of its motion
/// for parked bodies (both boxes already hold Bullet's contact threshold).
constexpr double kWakeMargin = 0.01;
/// m: a sleeping body is parked only when it is this much farther still from
/// every awake body's reach, lest it be parked and woken by turns.
constexpr double kParkMargin = 0.02;

void CheckPositive(double value, const char* what) {
  if (!(value > 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("PhysicsWorld: ") + what + " must be finite and > 0");
  }
}

}  // namespace

namespace {

/// DESIGN.md: sleeping bodies cost nothing. Bullet's world damps and
/// integrates every dynamic body before each step (predictUnconstraintMotion:
/// two pow, a quaternion update), asleep or not — a fifth of a step with 1000
/// sleeping boxes. A sleeping body's velocity is zero (Bullet zeroes it when
/// the body falls asleep), so skipping it changes no result; Bullet's own
/// integrateTransforms skips it the same way.
///
/// A step can also be cut short: one step of thousands of overlapping bodies
/// takes seconds (minutes for the first, which creates every contact), and a
/// stopping session must not wait for it. Once `cancel` is set, the step's
/// remaining phases do nothing (see CancellableDispatcher and
/// CancellableSolver for the long loops inside them); the world is left
/// mid-step, to be stopped.
class SleepAwareWorld final : public btDiscreteDynamicsWorld {
 public:
  SleepAwareWorld(btDispatcher* dispatcher, btBroadphaseInterface* broadphase,
                  btConstraintSolver* solver, btCollisionConfiguration* config,
                  const std::atomic<bool>& cancel)
      : btDiscreteDynamicsWorld(dispatcher, broadphase, solver, config), cancel_(cancel) {}

  void performDiscreteCollisionDetection() override {
    if (!cancelled()) btDiscreteDynamicsWorld::performDiscreteCollisionDetection();
  }
  /// Bullet's, body by body: moving a body's box makes the broadphase meet
  /// it with every box it overlaps, milliseconds each in a pile.
  void updateAabbs() override {
    for (int i = 0; i < m_collisionObjects.size(); ++i) {
      if (cancelled()) return;
      btCollisionObject* object = m_collisionObjects[i];
      if (m_forceUpdateAllAabbs || object->isActive()) updateSingleAabb(object);
    }
  }
  void computeOverlappingPairs() override {
    if (!cancelled()) btDiscreteDynamicsWorld::computeOverlappingPairs();
  }

 protected:
  void predictUnconstraintMotion(btScalar step) override {
    for (int i = 0; i < m_nonStaticRigidBodies.size(); ++i) {
      btRigidBody* body = m_nonStaticRigidBodies[i];
      if (body->isStaticOrKinematicObject() || !body->isActive()) continue;
      body->applyDamping(step);
      body->predictIntegratedTransform(step, body->getInterpolationWorldTransform());
    }
  }
  void calculateSimulationIslands() override {
    if (!cancelled()) btDiscreteDynamicsWorld::calculateSimulationIslands();
  }
  void solveConstraints(btContactSolverInfo& info) override {
    if (!cancelled()) btDiscreteDynamicsWorld::solveConstraints(info);
  }
  void integrateTransforms(btScalar step) override {
    if (!cancelled()) btDiscreteDynamicsWorld::integrateTransforms(step);
  }
  void updateActivationState(btScalar step) override {
    if (!cancelled()) btDiscreteDynamicsWorld::updateActivationState(step);
  }

 private:
  bool cancelled() const { return cancel_.load(std::memory_order_relaxed); }
  const std::atomic<bool>& cancel_;
};

/// How often the long loops look at the cancel flag (pairs, manifolds).
constexpr int kCancelCheckEvery = 256;

/// The narrow phase, pair by pair as Bullet's own (a hashed pair cache,
/// non-deterministic order: what btDbvtBroadphase uses), and given up once
/// `cancel` is set: the first step of a pile of overlapping bodies spends
/// its minutes here, creating a contact manifold per pair.
class CancellableDispatcher final : public btCollisionDispatcher {
 public:
  CancellableDispatcher(btCollisionConfiguration* config, const std::atomic<bool>& cancel)
      : btCollisionDispatcher(config), cancel_(cancel) {}

  void dispatchAllCollisionPairs(btOverlappingPairCache* cache, const btDispatcherInfo& info,
                                 btDispatcher* /*dispatcher*/) override {
    btBroadphasePairArray& pairs = cache->getOverlappingPairArray();
    for (int i = 0; i < pairs.size(); ++i) {
      if (i % kCancelCheckEvery == 0 && cancel_.load(std::memory_order_relaxed)) return;
      getNearCallback()(pairs[i], *this, info);
    }
  }

 private:
  const std::atomic<bool>& cancel_;
};

/// The broadphase's pair table, which stops taking pairs once `cancel` is
/// set: the first step after a pile of thousands of overlapping bodies is
/// built meets every pair there (bodies are met at the next step, see the
/// constructor), tens of millions of them, with table rehashes on the way.
/// A cancelled step's world may lack pairs: it is to be stopped, not stepped.
class CancellablePairCache final : public btHashedOverlappingPairCache {
 public:
  explicit CancellablePairCache(const std::atomic<bool>& cancel) : cancel_(cancel) {}

  btBroadphasePair* addOverlappingPair(btBroadphaseProxy* a, btBroadphaseProxy* b) override {
    if (cancel_.load(std::memory_order_relaxed)) return nullptr;  // the caller ignores it
    return btHashedOverlappingPairCache::addOverlappingPair(a, b);
  }

 private:
  const std::atomic<bool>& cancel_;
};

/// The solver, given up once `cancel` is set: between manifolds while it
/// turns contacts into constraints, and between iterations.
class CancellableSolver final : public btSequentialImpulseConstraintSolver {
 public:
  explicit CancellableSolver(const std::atomic<bool>& cancel) : cancel_(cancel) {}

 protected:
  void convertContacts(btPersistentManifold** manifolds, int count,
                       const btContactSolverInfo& info) override {
    for (int i = 0; i < count; ++i) {
      if (i % kCancelCheckEvery == 0 && cancel_.load(std::memory_order_relaxed)) return;
      convertContact(manifolds[i], info);
    }
  }
  btScalar solveSingleIteration(int iteration, btCollisionObject** bodies, int body_count,
                                btPersistentManifold** manifolds, int manifold_count,
                                btTypedConstraint** constraints, int constraint_count,
                                const btContactSolverInfo& info, btIDebugDraw* draw) override {
    // A residual of 0 ends Bullet's iteration loop.
    if (cancel_.load(std::memory_order_relaxed)) return 0.0;
    return btSequentialImpulseConstraintSolver::solveSingleIteration(
        iteration, bodies, body_count, manifolds, manifold_count, constraints, constraint_count,
        info, draw);
  }

 private:
  const std::atomic<bool>& cancel_;
};

}  // namespace

struct PhysicsWorld::Body {
  std::vector<std::unique_ptr<btCollisionShape>> parts;  ///< a compound's children: outlive it
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> body;
  btTransform spawn;
  // Parking (see world.hpp). While parked the body is out of the Bullet
  // world; what Bullet would lose with it is kept here.
  btDbvtNode* leaf = nullptr;  ///< its box in the parked tree: non-null while parked
  int group = 0, mask = 0;     ///< its collision filter
  btVector3 gravity{0, 0, 0};  ///< m/s² (adding a body sets the world's)
  bool queued = false;         ///< on this pass's list to park or to wake
};

/// What an awake body can reach before the next step's contacts: its
/// broadphase box grown by its motion, and its collision filter.
struct PhysicsWorld::Reach {
  btVector3 min, max;
  int group = 0, mask = 0;
  const btCollisionObject* object = nullptr;
};

/// The Bullet machinery, in construction order (destroyed in reverse). A
/// step gives up once `cancel` is set (PhysicsWorld::RequestStop).
struct PhysicsWorld::Bullet {
  explicit Bullet(const std::atomic<bool>& cancel)
      : dispatcher(&collision_config, cancel),
        pairs(cancel),
        broadphase(&pairs),
        solver(cancel),
        world(&dispatcher, &broadphase, &solver, &collision_config, cancel) {}

  btDefaultCollisionConfiguration collision_config;
  CancellableDispatcher dispatcher;
  CancellablePairCache pairs;
  btDbvtBroadphase broadphase;
  CancellableSolver solver;
  SleepAwareWorld world;
  // Parking: the parked bodies' boxes (leaf data: Body*), and each pass's
  // lists, reserved ahead (AddBody; movers when the world grows).
  btDbvt parked;
  std::vector<Reach> movers;
  std::vector<Body*> to_wake;
  std::vector<Body*> to_park;
};

PhysicsWorld::PhysicsWorld(const PhysicsConfig& config)
    : config_(Validated(config)), bullet_(std::make_unique<Bullet>(stop_requested_)) {
  g_worlds_created.fetch_add(1);
  gCalculateCombinedFrictionCallback = &AverageFriction;
  gCalculateCombinedRestitutionCallback = &AverageRestitution;
  gCalculateCombinedRollingFrictionCallback = &SumRollingFriction;
  gCalculateCombinedSpinningFrictionCallback = &SumSpinningFriction;
  btDiscreteDynamicsWorld& w = bullet_->world;
  // Bounding boxes of active bodies only: static and sleeping ones do not
  // move (Bullet's default recomputes every body's box each step). Code that
  // moves a body by hand refreshes its box (ForgetContacts).
  w.setForceUpdateAllAabbs(false);
  // A body added is met with the bodies it overlaps at the next step, on the
  // stepping thread, not in AddRigidBody: building a pile of thousands of
  // overlapping bodies would otherwise spend seconds in single, uninterruptible
  // pair-table rehashes on the session's thread before the run even starts.
  bullet_->broadphase.m_deferedcollide = true;
  w.setGravity(ToBt(config_.gravity));
  btContactSolverInfo& info = w.getSolverInfo();
  info.m_numIterations = config_.solver_iterations;
}

PhysicsWorld::~PhysicsWorld() {
  Stop();
  ForgetAllPairs();
  for (auto& h : hands_) h.reset();  // removes its bodies and joints from the world
  for (auto& b : bodies_) {
    if (b->leaf == nullptr) bullet_->world.removeRigidBody(b->body.get());  // parked: not in it
  }
  bodies_.clear();
}

void PhysicsWorld::ForgetAllPairs() {
  // Removing a body makes Bullet walk every overlapping pair twice (to clean
  // and to drop the body's own): tearing down n bodies costs n times the
  // pairs, half a minute for 3000 overlapping spheres. Dropping the pairs
  // first, each from the end of the cache, costs one visit per pair.
  btOverlappingPairCache* cache = bullet_->broadphase.getOverlappingPairCache();
  btBroadphasePairArray& pairs = cache->getOverlappingPairArray();
  while (pairs.size() > 0) {
    const btBroadphasePair& last = pairs[pairs.size() - 1];
    cache->removeOverlappingPair(last.m_pProxy0, last.m_pProxy1, &bullet_->dispatcher);
  }
}

std::unique_ptr<PhysicsWorld> PhysicsWorld::CreateIfNeeded(const PhysicsConfig& config,
                                                           const PhysicsNeeds& needs) {
  if (!NeedsWorld(needs)) return nullptr;
  return std::make_unique<PhysicsWorld>(config);
}

uint64_t PhysicsWorld::worlds_created() { return g_worlds_created.load(); }

btDiscreteDynamicsWorld& PhysicsWorld::bullet() { return bullet_->world; }

BodyId PhysicsWorld::AddBody(std::unique_ptr<Body> body) {
  const auto id = static_cast<BodyId>(bodies_.size());
  body->body->setUserIndex(id);  // from Bullet's objects back to ours (parking)
  bodies_.push_back(std::move(body));
  // The parking passes' lists, here rather than in the loop.
  bullet_->to_wake.reserve(bodies_.size());
  bullet_->to_park.reserve(bodies_.size());
  return id;
}

namespace {
std::unique_ptr<btRigidBody> MakeBody(btCollisionShape* shape, double mass, const btTransform& pose,
                                      const PhysicsMaterial& material) {
  btVector3 inertia(0, 0, 0);
  if (mass > 0.0) shape->calculateLocalInertia(mass, inertia);
  btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
  info.m_startWorldTransform = pose;
  auto body = std::make_unique<btRigidBody>(info);
  SetMaterial(*body, material);
  return body;
}
}  // namespace

BodyId PhysicsWorld::AddStaticPlane(const Vec3d& normal, double offset,
                                    const PhysicsMaterial& material) {
  btVector3 n = ToBt(normal);
  CheckPositive(n.length(), "plane normal length");
  n.normalize();
  auto b = std::make_unique<Body>();
  b->shape = std::make_unique<btStaticPlaneShape>(n, offset);
  b->spawn = btTransform::getIdentity();
  b->body = MakeBody(b->shape.get(), 0.0, b->spawn, material);
  bullet_->world.addRigidBody(b->body.get());
  return AddBody(std::move(b));
}

BodyId PhysicsWorld::AddStaticBox(const Vec3d& center, const Vec3d& half_extents,
                                  const PhysicsMaterial& material) {
  for (double e : half_extents) CheckPositive(e, "box half extent");
  auto b = std::make_unique<Body>();
  b->shape = std::make_unique<btBoxShape>(ToBt(half_extents));
  b->shape->setMargin(BoxMargin(half_extents));
  b->spawn = btTransform(btQuaternion::getIdentity(), ToBt(center));
  b->body = MakeBody(b->shape.get(), 0.0, b->spawn, material);
  bullet_->world.addRigidBody(b->body.get());
  return AddBody(std::move(b));
}

BodyId PhysicsWorld::AddDynamicBox(const Vec3d& center, const Vec3d& half_extents, double mass,
                                   const PhysicsMaterial& material) {
  for (double e : half_extents) CheckPositive(e, "box half extent");
  CheckPositive(mass, "box mass");
  auto b = std::make_unique<Body>();
  b->shape = std::make_unique<btBoxShape>(ToBt(half_extents));
  b->shape->setMargin(BoxMargin(half_extents));
  b->spawn = btTransform(btQuaternion::getIdentity(), ToBt(center));
  b->body = MakeBody(b->shape.get(), mass, b->spawn, material);
  bullet_->world.addRigidBody(b->body.get());
  return AddBody(std::move(b));
}

BodyId PhysicsWorld::AddDynamicSphere(const Vec3d& center, double radius, double mass,
                                      const PhysicsMaterial& material) {
  CheckPositive(radius, "sphere radius");
  CheckPositive(mass, "sphere mass");
  auto b = std::make_unique<Body>();
  b->shape = std::make_unique<btSphereShape>(radius);
  b->spawn = btTransform(btQuaternion::getIdentity(), ToBt(center));
  b->body = MakeBody(b->shape.get(), mass, b->spawn, material);
  bullet_->world.addRigidBody(b->body.get());
  return AddBody(std::move(b));
}

BodyId PhysicsWorld::AddRigidBody(std::unique_ptr<btCollisionShape> shape,
                                  std::vector<std::unique_ptr<btCollisionShape>> parts, double mass,
                                  const Vec3d& principal_inertia, const Pose& pose,
                                  const PhysicsMaterial& material) {
  if (!shape) throw std::invalid_argument("PhysicsWorld: AddRigidBody without a shape");
  if (!(mass >= 0.0) || !std::isfinite(mass)) {
    throw std::invalid_argument("PhysicsWorld: body mass must be finite and >= 0");
  }
  if (mass > 0.0) {
    for (double i : principal_inertia) CheckPositive(i, "principal inertia");
  }
  const auto& q = pose.orientation;
  btQuaternion rotation(q[1], q[2], q[3], q[0]);
  CheckPositive(rotation.length(), "pose quaternion length");
  rotation.normalize();
  auto b = std::make_unique<Body>();
  b->parts = std::move(parts);
  b->shape = std::move(shape);
  b->spawn = btTransform(rotation, ToBt(pose.position));
  const btVector3 inertia = mass > 0.0 ? ToBt(principal_inertia) : btVector3(0, 0, 0);
  btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, b->shape.get(), inertia);
  info.m_startWorldTransform = b->spawn;
  b->body = std::make_unique<btRigidBody>(info);
  SetMaterial(*b->body, material);
  bullet_->world.addRigidBody(b->body.get());
  return AddBody(std::move(b));
}

ProxyHand& PhysicsWorld::AddHand(Side side) {
  auto& slot = hands_[haptics::Index(side)];
  if (!slot) slot = std::make_unique<ProxyHand>(bullet_->world, config_.hand, config_.step_s, side);
  return *slot;
}

btRigidBody& PhysicsWorld::body(BodyId id) {
  Body& b = *bodies_.at(static_cast<size_t>(id));
  if (b.leaf != nullptr) Unpark(b);
  return *b.body;
}
const btRigidBody& PhysicsWorld::body(BodyId id) const {
  return *bodies_.at(static_cast<size_t>(id))->body;
}
bool PhysicsWorld::BodyParked(BodyId id) const {
  return bodies_.at(static_cast<size_t>(id))->leaf != nullptr;
}
Pose PhysicsWorld::BodyPose(BodyId id) const {
  return ToPose(bodies_.at(static_cast<size_t>(id))->body->getWorldTransform());
}
Vec3d PhysicsWorld::BodyVelocity(BodyId id) const {
  return ToVec(bodies_.at(static_cast<size_t>(id))->body->getLinearVelocity());
}
bool PhysicsWorld::BodySleeping(BodyId id) const {
  return bodies_.at(static_cast<size_t>(id))->body->getActivationState() == ISLAND_SLEEPING;
}

void PhysicsWorld::Step() {
  // The step's cost on the real clock, also in a simulated-time run.
  const int64_t t0 = RealMonotonicNs();
  for (auto& h : hands_) {
    if (h) h->PrepareStep();
  }
  for (StepHook* hook : hooks_) hook->BeforeStep();
  WakeParked();
  // maxSubSteps = 0: exactly one step of step_s (the thread keeps the rate).
  bullet_->world.stepSimulation(config_.step_s, 0);
  CheckFinite();
  // A step cut short leaves the world mid-step: to be stopped, not tidied.
  if (!stop_requested_.load(std::memory_order_relaxed)) ParkSleeping();
  for (StepHook* hook : hooks_) hook->AfterStep();
  ++counters_.steps;
  counters_.last_step_us = static_cast<double>(RealMonotonicNs() - t0) * 1e-3;
  counters_.max_step_us = std::max(counters_.max_step_us, counters_.last_step_us);
  for (int s = 0; s < haptics::kSides; ++s) {
    if (hands_[s]) poses_[s].Store(hands_[s]->Snapshot(last_tick_ns_));
  }
  published_counters_.Store(counters_);
}

void PhysicsWorld::CheckFinite() {
  for (auto& h : hands_) {
    if (h && !h->Finite()) {
      h->Reset();
      ++counters_.hand_resets;
    }
  }
  // The scene's bodies in the world (parked ones are not: asleep, they did
  // not move); a sleeping body did not move this step either: it is as
  // finite as when it fell asleep.
  const btAlignedObjectArray<btRigidBody*>& in_world = bullet_->world.getNonStaticRigidBodies();
  for (int i = 0; i < in_world.size(); ++i) {
    btRigidBody& body = *in_world[i];
    Body* b = SceneBody(body);
    if (b == nullptr || body.isStaticOrKinematicObject() || !body.isActive() || IsFinite(body)) {
      continue;
    }
    body.setWorldTransform(b->spawn);
    body.setInterpolationWorldTransform(b->spawn);
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    body.setInterpolationLinearVelocity(btVector3(0, 0, 0));
    body.setInterpolationAngularVelocity(btVector3(0, 0, 0));
    body.clearForces();
    body.forceActivationState(ACTIVE_TAG);
    ForgetContacts(bullet_->world, body);
    ++counters_.body_resets;
  }
}

PhysicsWorld::Body* PhysicsWorld::SceneBody(const btCollisionObject& object) {
  const int id = object.getUserIndex();
  if (id < 0 || static_cast<size_t>(id) >= bodies_.size()) return nullptr;
  Body* b = bodies_[static_cast<size_t>(id)].get();
  return b->body.get() == &object ? b : nullptr;
}

void PhysicsWorld::WakeParked() {
  Bullet& bt = *bullet_;
  // Every awake body that collides with anything reaches as far as its
  // broadphase box (which holds Bullet's contact threshold), grown by two
  // steps of its motion (the box is a step old; the next step's contacts
  // are found where it is now) and a margin.
  const btAlignedObjectArray<btRigidBody*>& in_world = bt.world.getNonStaticRigidBodies();
  bt.movers.clear();
  const auto n = static_cast<size_t>(in_world.size());
  if (bt.movers.capacity() < n) bt.movers.reserve(2 * n);  // only when the world grew
  const double reach_s = 2.0 * config_.step_s;
  for (int i = 0; i < in_world.size(); ++i) {
    const btRigidBody& body = *in_world[i];
    const btBroadphaseProxy* proxy = body.getBroadphaseHandle();
    if (!body.isActive() || proxy == nullptr || proxy->m_collisionFilterMask == 0) continue;
    const btVector3 half = 0.5 * (proxy->m_aabbMax - proxy->m_aabbMin);
    const double speed =
        body.getLinearVelocity().length() + body.getAngularVelocity().length() * half.length();
    const double grow = speed * reach_s + kWakeMargin;
    // A NaN speed (CheckFinite resets the body after the step) reaches everywhere.
    const btVector3 g = std::isfinite(grow)
                            ? btVector3(grow, grow, grow)
                            : btVector3(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
    bt.movers.push_back({proxy->m_aabbMin - g, proxy->m_aabbMax + g, proxy->m_collisionFilterGroup,
                         proxy->m_collisionFilterMask, &body});
  }
  if (parked_count_ == 0) return;

  /// Parked bodies whose box meets a volume and whose filter meets the
  /// asker's, each once, onto to_wake.
  struct Hits final : btDbvt::ICollide {
    using btDbvt::ICollide::Process;
    Hits(int g, int m, std::vector<Body*>& o) : group(g), mask(m), out(o) {}
    void Process(const btDbvtNode* leaf) override {
      Body& b = *static_cast<Body*>(leaf->data);
      if (b.queued || (group & b.mask) == 0 || (b.group & mask) == 0) return;
      b.queued = true;
      out.push_back(&b);
    }
    int group, mask;
    std::vector<Body*>& out;
  };
  bt.to_wake.clear();
  for (const Reach& m : bt.movers) {
    Hits hits(m.group, m.mask, bt.to_wake);
    bt.parked.collideTV(bt.parked.m_root, btDbvtVolume::FromMM(m.min, m.max), hits);
  }
  // And what touches a body woken (their boxes meet: within Bullet's contact
  // threshold), and so on: its sleeping island, woken together as Bullet would.
  for (size_t i = 0; i < bt.to_wake.size(); ++i) {
    const Body& b = *bt.to_wake[i];
    Hits hits(b.group, b.mask, bt.to_wake);
    bt.parked.collideTV(bt.parked.m_root, b.leaf->volume, hits);
  }
  for (Body* b : bt.to_wake) {
    b->queued = false;
    Unpark(*b);
    b->body->activate(true);
  }
}

void PhysicsWorld::Unpark(Body& b) {
  Bullet& bt = *bullet_;
  bt.parked.remove(b.leaf);
  b.leaf = nullptr;
  --parked_count_;
  ++counters_.wakings;
  // Back as it left: asleep (ISLAND_SLEEPING kept), at rest, its filter,
  // gravity and broadphase box (adding one leaves out the contact threshold,
  // and a sleeping body's box is not refreshed). Its pairs are found by the
  // next step's broadphase pass.
  bt.world.addRigidBody(b.body.get(), b.group, b.mask);
  b.body->setGravity(b.gravity);
  bt.world.updateSingleAabb(b.body.get());
}

void PhysicsWorld::ParkSleeping() {
  Bullet& bt = *bullet_;
  const btAlignedObjectArray<btRigidBody*>& in_world = bt.world.getNonStaticRigidBodies();
  uint64_t awake = 0;
  bt.to_park.clear();
  const btVector3 park_margin(kParkMargin, kParkMargin, kParkMargin);
  for (int i = 0; i < in_world.size(); ++i) {
    btRigidBody& body = *in_world[i];
    Body* b = SceneBody(body);
    if (b == nullptr || body.isStaticOrKinematicObject()) continue;
    if (body.isActive()) {
      ++awake;
      continue;
    }
    // Bullet keeps a sleeping body's joints in its islands: one with joints stays.
    const btBroadphaseProxy* proxy = body.getBroadphaseHandle();
    if (!parking_ || body.getActivationState() != ISLAND_SLEEPING ||
        body.getNumConstraintRefs() > 0 || proxy == nullptr) {
      continue;
    }
    // Asleep within the reach of a body still awake (and then some: it
    // would be woken at once): it stays, asleep, until the mover leaves or
    // wakes it. (Bodies that fell asleep in this step were movers before it.)
    const btVector3 lo = proxy->m_aabbMin - park_margin, hi = proxy->m_aabbMax + park_margin;
    bool near = false;
    for (const Reach& m : bt.movers) {
      if (m.object->isActive() && (m.group & proxy->m_collisionFilterMask) != 0 &&
          (proxy->m_collisionFilterGroup & m.mask) != 0 &&
          TestAabbAgainstAabb2(lo, hi, m.min, m.max)) {
        near = true;
        break;
      }
    }
    if (near) continue;
    b->queued = true;
    bt.to_park.push_back(b);
  }
  if (!bt.to_park.empty()) {
    // Their pairs first, in one pass over the pair table: removing a body
    // makes Bullet walk every pair twice (see ForgetAllPairs), here only the
    // pairs that are left. From the end: a removed pair's slot takes the
    // last pair, already looked at.
    btOverlappingPairCache* cache = bt.broadphase.getOverlappingPairCache();
    btBroadphasePairArray& pairs = cache->getOverlappingPairArray();
    const auto parking = [&](const btBroadphaseProxy* p) {
      const Body* b = SceneBody(*static_cast<const btCollisionObject*>(p->m_clientObject));
      return b != nullptr && b->queued;
    };
    for (int i = pairs.size() - 1; i >= 0; --i) {
      btBroadphasePair& pair = pairs[i];
      if (parking(pair.m_pProxy0) || parking(pair.m_pProxy1)) {
        cache->removeOverlappingPair(pair.m_pProxy0, pair.m_pProxy1, &bt.dispatcher);
      }
    }
    for (Body* b : bt.to_park) {
      btRigidBody& body = *b->body;
      const btBroadphaseProxy* proxy = body.getBroadphaseHandle();
      b->group = proxy->m_collisionFilterGroup;
      b->mask = proxy->m_collisionFilterMask;
      b->gravity = body.getGravity();
      const btDbvtVolume box = btDbvtVolume::FromMM(proxy->m_aabbMin, proxy->m_aabbMax);
      // Asleep, Bullet zeroed its velocities; its forces are cleared each step.
      bt.world.removeRigidBody(&body);
      b->leaf = bt.parked.insert(box, b);
      b->queued = false;
      ++parked_count_;
      ++counters_.parkings;
    }
  }
  counters_.parked_bodies = parked_count_;
  counters_.awake_bodies = awake;
}

void PhysicsWorld::SetParking(bool on) {
  parking_ = on;
  if (on) return;
  for (auto& b : bodies_) {
    if (b->leaf != nullptr) Unpark(*b);
  }
  counters_.parked_bodies = 0;
  published_counters_.Store(counters_);
}

bool PhysicsWorld::EnterHal() {
  hal_users_.fetch_add(1);
  if (!stop_requested_.load()) return true;
  hal_users_.fetch_sub(1);
  return false;
}

void PhysicsWorld::LeaveHal() { hal_users_.fetch_sub(1); }

void PhysicsWorld::Tick(haptics::Hal& hal, int64_t now_ns) {
  last_tick_ns_ = now_ns;
  // The HAL only between EnterHal and LeaveHal, and only to copy in and out
  // (placing a hand the first time walks every contact pair: not in there):
  // once a stop is requested this thread never touches it again (RequestStop).
  std::array<haptics::HandSample, haptics::kSides> samples{};
  if (!EnterHal()) return;
  for (int s = 0; s < haptics::kSides; ++s) {
    if (hands_[s]) samples[s] = hal.LatestSample(static_cast<Side>(s));
  }
  LeaveHal();
  for (int s = 0; s < haptics::kSides; ++s) {
    tracked_ok_[s] = false;
    if (!hands_[s]) continue;
    tracked_ok_[s] = hands_[s]->SetTracked(samples[s]);
    if (!tracked_ok_[s]) ++counters_.invalid_samples;
  }
  Step();
  if (!EnterHal()) return;
  for (int s = 0; s < haptics::kSides; ++s) {
    if (!hands_[s]) continue;
    const Side side = static_cast<Side>(s);
    haptics::ForceSetpoint sp = hal.Setpoint(side);
    if (tracked_ok_[s] && hands_[s]->placed()) {
      hands_[s]->FillSetpoint(sp);
    } else {
      // No tracked hand: no coupling to render (the interface's field stays).
      sp.coupling_enabled = false;
      sp.finger_forces = {};
    }
    hal.SetSetpoint(side, sp, now_ns);
    ++counters_.setpoints;
  }
  LeaveHal();
  published_counters_.Store(counters_);
}

void PhysicsWorld::Start(haptics::Hal& hal) {
  if (running_.load()) return;
  hal_ = &hal;
  stop_requested_.store(false);
  PeriodicThread::Options options;
  options.name = "physics";
  options.rate_hz = 1.0 / config_.step_s;
  options.realtime_priority = config_.realtime_priority;
  thread_ =
      std::make_unique<PeriodicThread>(options, [this](int64_t now_ns) { Tick(*hal_, now_ns); });
  running_.store(true);
  thread_->Start();
}

void PhysicsWorld::RequestStop() {
  if (!running_.load() || stop_requested_.load()) return;
  stop_requested_.store(true);
  thread_->RequestStop();
  // Wait out a HAL access in progress (a copy, microseconds; never the step):
  // after this the thread does not touch the HAL again, and this thread is
  // the set-points' only writer.
  while (hal_users_.load() != 0) std::this_thread::yield();
  for (int s = 0; s < haptics::kSides; ++s) {
    if (!hands_[s]) continue;
    const Side side = static_cast<Side>(s);
    haptics::ForceSetpoint sp = hal_->Setpoint(side);
    sp.coupling_enabled = false;
    sp.finger_forces = {};
    hal_->SetSetpoint(side, sp, MonotonicNs());
  }
}

bool PhysicsWorld::Stop(double timeout_s) {
  if (!running_.load()) return true;
  RequestStop();
  if (!thread_->StopWithin(timeout_s)) return false;
  running_.store(false);
  return true;
}

void PhysicsWorld::Stop() {
  if (!running_.load()) return;
  RequestStop();
  thread_->Stop();
  running_.store(false);
}

LoopStats PhysicsWorld::Stats() const { return thread_ ? thread_->Stats() : LoopStats{}; }

}  // namespace haptel::physics
