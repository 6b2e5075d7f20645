#include "haptel/physics/world.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "bullet_util.hpp"
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
class SleepAwareWorld final : public btDiscreteDynamicsWorld {
 public:
  using btDiscreteDynamicsWorld::btDiscreteDynamicsWorld;

 protected:
  void predictUnconstraintMotion(btScalar step) override {
    for (int i = 0; i < m_nonStaticRigidBodies.size(); ++i) {
      btRigidBody* body = m_nonStaticRigidBodies[i];
      if (body->isStaticOrKinematicObject() || !body->isActive()) continue;
      body->applyDamping(step);
      body->predictIntegratedTransform(step, body->getInterpolationWorldTransform());
    }
  }
};

}  // namespace

/// The Bullet machinery, in construction order (destroyed in reverse).
struct PhysicsWorld::Bullet {
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  SleepAwareWorld world{&dispatcher, &broadphase, &solver, &collision_config};
};

struct PhysicsWorld::Body {
  std::vector<std::unique_ptr<btCollisionShape>> parts;  ///< a compound's children: outlive it
  std::unique_ptr<btCollisionShape> shape;
  std::unique_ptr<btRigidBody> body;
  btTransform spawn;
};

PhysicsWorld::PhysicsWorld(const PhysicsConfig& config)
    : config_(config), bullet_(std::make_unique<Bullet>()) {
  CheckPositive(config_.step_s, "step_s");
  if (config_.solver_iterations < 1)
    throw std::invalid_argument("PhysicsWorld: solver_iterations must be >= 1");
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
  w.setGravity(ToBt(config_.gravity));
  btContactSolverInfo& info = w.getSolverInfo();
  info.m_numIterations = config_.solver_iterations;
}

PhysicsWorld::~PhysicsWorld() {
  Stop();
  for (auto& h : hands_) h.reset();  // removes its bodies and joints from the world
  for (auto& b : bodies_) bullet_->world.removeRigidBody(b->body.get());
  bodies_.clear();
}

std::unique_ptr<PhysicsWorld> PhysicsWorld::CreateIfNeeded(const PhysicsConfig& config,
                                                           const PhysicsNeeds& needs) {
  if (!NeedsWorld(needs)) return nullptr;
  return std::make_unique<PhysicsWorld>(config);
}

uint64_t PhysicsWorld::worlds_created() { return g_worlds_created.load(); }

btDiscreteDynamicsWorld& PhysicsWorld::bullet() { return bullet_->world; }

BodyId PhysicsWorld::AddBody(std::unique_ptr<Body> body) {
  bodies_.push_back(std::move(body));
  return static_cast<BodyId>(bodies_.size() - 1);
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

btRigidBody& PhysicsWorld::body(BodyId id) { return *bodies_.at(static_cast<size_t>(id))->body; }
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
  const int64_t t0 = MonotonicNs();
  for (auto& h : hands_) {
    if (h) h->PrepareStep();
  }
  for (StepHook* hook : hooks_) hook->BeforeStep();
  // maxSubSteps = 0: exactly one step of step_s (the thread keeps the rate).
  bullet_->world.stepSimulation(config_.step_s, 0);
  CheckFinite();
  for (StepHook* hook : hooks_) hook->AfterStep();
  ++counters_.steps;
  counters_.last_step_us = static_cast<double>(MonotonicNs() - t0) * 1e-3;
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
  for (auto& b : bodies_) {
    btRigidBody& body = *b->body;
    // A sleeping body did not move this step: it is as finite as when it fell asleep.
    if (body.isStaticOrKinematicObject() || !body.isActive() || IsFinite(body)) continue;
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

void PhysicsWorld::Tick(haptics::Hal& hal, int64_t now_ns) {
  last_tick_ns_ = now_ns;
  for (int s = 0; s < haptics::kSides; ++s) {
    tracked_ok_[s] = false;
    if (!hands_[s]) continue;
    const Side side = static_cast<Side>(s);
    tracked_ok_[s] = hands_[s]->SetTracked(hal.LatestSample(side));
    if (!tracked_ok_[s]) ++counters_.invalid_samples;
  }
  Step();
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
  published_counters_.Store(counters_);
}

void PhysicsWorld::Start(haptics::Hal& hal) {
  if (running_.load()) return;
  hal_ = &hal;
  PeriodicThread::Options options;
  options.name = "physics";
  options.rate_hz = 1.0 / config_.step_s;
  options.realtime_priority = config_.realtime_priority;
  thread_ =
      std::make_unique<PeriodicThread>(options, [this](int64_t now_ns) { Tick(*hal_, now_ns); });
  running_.store(true);
  thread_->Start();
}

void PhysicsWorld::Stop() {
  if (!running_.load()) return;
  thread_->Stop();
  running_.store(false);
  for (int s = 0; s < haptics::kSides; ++s) {
    if (!hands_[s]) continue;
    const Side side = static_cast<Side>(s);
    haptics::ForceSetpoint sp = hal_->Setpoint(side);
    sp.coupling_enabled = false;
    sp.finger_forces = {};
    hal_->SetSetpoint(side, sp, MonotonicNs());
  }
}

LoopStats PhysicsWorld::Stats() const { return thread_ ? thread_->Stats() : LoopStats{}; }

}  // namespace haptel::physics
