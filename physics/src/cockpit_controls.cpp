#include "haptel/physics/cockpit_controls.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "bullet_util.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/physics/world.hpp"

// ---------------------------------------------------------------------------
// Which Bullet formulation, and why
//
// Each control is ONE btGeneric6DofSpring2Constraint to the fixed world (the
// one-body constructor), like the proxy hand's joints: five axes locked, one
// free between its end stops (wheel: angular X within ±max angle — the first
// axis of RO_XYZ has the full ±π range; throttle: linear X within ±travel).
// Everything the interface asks for is an axis setting that persists across
// steps, solved with the contacts in the same sequential-impulse pass:
//   - the return-to-zero spring and the column's damping: Bullet's own spring
//     on the free axis (explicit; the values are far below its clamp: 0.6
//     N·m/rad on 4.3e-3 kg·m² is ω·h ≈ 0.012, 60 N/m on 0.1 kg ω·h ≈ 0.025);
//   - the wheel torque (shake): the axis's motor, not a servo, with a target
//     velocity far out of reach in the torque's direction and a maximum force
//     of |torque|, i.e. a constant torque inside the solver;
//   - the throttle lock: the free axis's limits set to [target, target] (a
//     hard stop row, like the locked axes), restored to ±travel on release.
// Not chosen: btHingeConstraint / btSliderConstraint (no spring, and a second
// set of conventions next to the hand's), and applyTorque / applyCentralForce
// (Bullet clears them after each step, and PhysicsWorld has no pre-step hook
// for bodies other than the hands).
//
// Shared control's guidance (cockpit-shared) is the one force that depends
// on where the controls are, a one-sided saturating spring in the controls'
// joint space (lever, rim arc), so no axis setting expresses it: a
// btActionInterface, which Bullet calls at the end of every step, evaluates
// it from the controls' positions and applies it as an impulse (force × step)
// on the knob and the wheel, acting in the following step's solve.
//
// Bullet reports the 6-DoF angle about X as the rotation of the body about
// −X (proxy_hand.cpp, SetTargets): with the frame's X along world +x that is
// exactly the wheel angle about −x (+ = left), so the limits, the spring's
// equilibrium and the motor's direction use the wheel angle as is.
// ---------------------------------------------------------------------------

namespace haptel::physics {
namespace {

/// The controls' collision group: they collide with the hands and dynamic
/// bodies, not with static ones (a table under the wheel must not jam it).
constexpr int kControlsGroup = 256;
constexpr int kControlsMask =
    btBroadphaseProxy::AllFilter & ~btBroadphaseProxy::StaticFilter & ~kControlsGroup;
/// Motor target speed standing for "as fast as the torque can push".
constexpr double kUnreachableSpeed = 1e4;

}  // namespace

void ControlsBodyConfig::ValidateOrThrow() const {
  namespace check = config_check;
  check::Positive("wheel_mass", wheel_mass);
  check::Positive("rim_radius", rim_radius);
  check::Whole("rim_segments", rim_segments, 6, 1000);
  check::NonNegative("wheel_damping", wheel_damping);
  check::Positive("knob_mass", knob_mass);
  for (double e : knob_half_extents) {
    if (!(e > 0.0) || !std::isfinite(e)) {
      check::Fail("knob_half_extents", "a list of 3 finite numbers > 0");
    }
  }
  check::NonNegative("throttle_damping", throttle_damping);
  check::Nested("material", material);
  check::NonNegative("contact_distance", contact_distance);
}

struct CockpitControlsBody::Impl {
  struct Control {
    std::unique_ptr<btCollisionShape> shape;
    std::vector<std::unique_ptr<btCollisionShape>> children;
    std::unique_ptr<btRigidBody> body;
    std::unique_ptr<btGeneric6DofSpring2Constraint> joint;
    btTransform spawn;
  };

  /// Bullet calls it after every step: shared control's guidance.
  struct GuidanceAction final : btActionInterface {
    explicit GuidanceAction(Impl& impl) : impl_(impl) {}
    void updateAction(btCollisionWorld*, btScalar step_s) override { impl_.PushGuidance(step_s); }
    void debugDraw(btIDebugDraw*) override {}
    Impl& impl_;
  };

  PhysicsWorld& world;
  CockpitConfig cockpit;
  ControlsBodyConfig config;
  double max_angle;
  Control wheel;
  Control knob;
  bool locked = false;
  int resets = 0;
  ControlsActuation guidance;   ///< the latest actuation's guidance fields (validated)
  double guidance_force = 0.0;  ///< N, at the latest step
  GuidanceAction guidance_action{*this};
  /// The proxy hands' bodies, gathered once: Read runs every physics step.
  std::vector<const btRigidBody*> hand;
  std::array<std::vector<bool>, 2>
      touching;  ///< per control (wheel, knob): which hand bodies touch it

  Impl(PhysicsWorld& w, const CockpitConfig& c, const ControlsBodyConfig& b)
      : world(w),
        cockpit(Validated(c)),
        config(Validated(b)),
        max_angle(c.wheel_max_angle_deg * M_PI / 180.0) {
    BuildWheel();
    BuildKnob();
    world.bullet().addAction(&guidance_action);
  }

  ~Impl() {
    btDiscreteDynamicsWorld& bw = world.bullet();
    bw.removeAction(&guidance_action);
    for (Control* c : {&wheel, &knob}) {
      bw.removeConstraint(c->joint.get());
      bw.removeRigidBody(c->body.get());
    }
  }

  void AddBody(Control& c, double mass, const btVector3& inertia) {
    btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, c.shape.get(), inertia);
    info.m_startWorldTransform = c.spawn;
    c.body = std::make_unique<btRigidBody>(info);
    SetMaterial(*c.body, config.material);
    // Two bodies: never asleep, so a new actuation acts without waking them.
    c.body->setActivationState(DISABLE_DEACTIVATION);
    c.body->setFlags(c.body->getFlags() | BT_DISABLE_WORLD_GRAVITY);
    world.bullet().addRigidBody(c.body.get(), kControlsGroup, kControlsMask);
    c.body->setGravity(btVector3(0, 0, 0));
  }

  void BuildWheel() {
    const double r = cockpit.wheel_radius;
    const int n = config.rim_segments;
    auto compound = std::make_unique<btCompoundShape>();
    // n capsules along the chords of the rim circle; their round ends overlap.
    const double half_angle = M_PI / n;
    const double chord = 2.0 * r * std::sin(half_angle);
    const double centre = r * std::cos(half_angle);
    for (int i = 0; i < n; ++i) {
      const btQuaternion q(btVector3(1, 0, 0), (2 * i + 1) * half_angle);
      const btMatrix3x3 basis(q);
      // Capsule axis (local y) tangent, its centre at local z on the chord.
      auto capsule = std::make_unique<btCapsuleShape>(config.rim_radius, chord);
      compound->addChildShape(btTransform(basis, basis * btVector3(0, 0, centre)), capsule.get());
      wheel.children.push_back(std::move(capsule));
    }
    wheel.shape = std::move(compound);
    wheel.spawn = btTransform(btQuaternion::getIdentity(), ToBt(cockpit.wheel_hub));
    // A thin ring: m·r² about its axis, m·r²/2 about a diameter.
    const double m = config.wheel_mass;
    AddBody(wheel, m, btVector3(m * r * r, 0.5 * m * r * r, 0.5 * m * r * r));

    wheel.joint = std::make_unique<btGeneric6DofSpring2Constraint>(
        *wheel.body, btTransform::getIdentity(), RO_XYZ);
    btGeneric6DofSpring2Constraint& j = *wheel.joint;
    j.setLinearLowerLimit(btVector3(0, 0, 0));
    j.setLinearUpperLimit(btVector3(0, 0, 0));
    j.setAngularLowerLimit(btVector3(-max_angle, 0, 0));
    j.setAngularUpperLimit(btVector3(max_angle, 0, 0));
    j.enableSpring(3, true);
    j.setStiffness(3, 0.0);
    j.setDamping(3, config.wheel_damping);
    j.setEquilibriumPoint(3, 0.0);
    world.bullet().addConstraint(&j, true);
  }

  void BuildKnob() {
    const auto& he = config.knob_half_extents;
    auto box = std::make_unique<btBoxShape>(ToBt(he));
    box->setMargin(BoxMargin(he));
    btVector3 inertia;
    box->calculateLocalInertia(config.knob_mass, inertia);
    knob.shape = std::move(box);
    knob.spawn = btTransform(btQuaternion::getIdentity(), ToBt(cockpit.throttle_centre));
    AddBody(knob, config.knob_mass, inertia);

    knob.joint = std::make_unique<btGeneric6DofSpring2Constraint>(
        *knob.body, btTransform::getIdentity(), RO_XYZ);
    btGeneric6DofSpring2Constraint& j = *knob.joint;
    j.setLinearLowerLimit(btVector3(-cockpit.throttle_travel, 0, 0));
    j.setLinearUpperLimit(btVector3(cockpit.throttle_travel, 0, 0));
    j.setAngularLowerLimit(btVector3(0, 0, 0));
    j.setAngularUpperLimit(btVector3(0, 0, 0));
    j.enableSpring(0, true);
    j.setStiffness(0, 0.0);
    j.setDamping(0, config.throttle_damping);
    j.setEquilibriumPoint(0, 0.0);
    world.bullet().addConstraint(&j, true);
  }

  double WheelAngle() const {
    // Where the rim's top (body +z) points, seen along the hinge axis.
    const btVector3 top = wheel.body->getWorldTransform().getBasis().getColumn(2);
    return std::atan2(top.y(), top.z());
  }
  double Throttle() const {
    return knob.body->getWorldTransform().getOrigin().x() - knob.spawn.getOrigin().x();
  }

  void PutBack(Control& c) {
    btRigidBody& b = *c.body;
    b.setWorldTransform(c.spawn);
    b.setInterpolationWorldTransform(c.spawn);
    b.setLinearVelocity(btVector3(0, 0, 0));
    b.setAngularVelocity(btVector3(0, 0, 0));
    b.setInterpolationLinearVelocity(btVector3(0, 0, 0));
    b.setInterpolationAngularVelocity(btVector3(0, 0, 0));
    b.clearForces();
    ForgetContacts(world.bullet(), b);
    ++resets;
  }

  /// Hand bodies touching the rim and the knob, each counted once per
  /// control (a compound rim has one manifold per touching capsule); one pass
  /// over the dispatcher's manifolds for both, as this runs every step.
  std::array<int, 2> HandContacts() {
    std::fill(touching[0].begin(), touching[0].end(), false);
    std::fill(touching[1].begin(), touching[1].end(), false);
    const std::array<const btCollisionObject*, 2> controls{wheel.body.get(), knob.body.get()};
    btDispatcher& d = *world.bullet().getDispatcher();
    for (int m = 0; m < d.getNumManifolds(); ++m) {
      const btPersistentManifold& pm = *d.getManifoldByIndexInternal(m);
      for (size_t c = 0; c < controls.size(); ++c) {
        const btCollisionObject* other = pm.getBody0() == controls[c]   ? pm.getBody1()
                                         : pm.getBody1() == controls[c] ? pm.getBody0()
                                                                        : nullptr;
        if (other == nullptr) continue;
        const auto it = std::find(hand.begin(), hand.end(), other);
        if (it == hand.end()) continue;
        for (int p = 0; p < pm.getNumContacts(); ++p) {
          if (pm.getContactPoint(p).getDistance() <= config.contact_distance) {
            touching[c][static_cast<size_t>(it - hand.begin())] = true;
            break;
          }
        }
      }
    }
    return {static_cast<int>(std::count(touching[0].begin(), touching[0].end(), true)),
            static_cast<int>(std::count(touching[1].begin(), touching[1].end(), true))};
  }

  /// Gathers the hands' bodies when a hand was added since the last call
  /// (allocates only then, i.e. on the first Read after set-up).
  void GatherHands() {
    size_t expected = 0;
    for (Side side : {Side::kLeft, Side::kRight}) {
      if (world.hand(side) != nullptr) expected += 1 + kFingers * kPhalanges;
    }
    if (expected == hand.size()) return;
    hand.clear();
    for (Side side : {Side::kLeft, Side::kRight}) {
      ProxyHand* h = world.hand(side);
      if (h == nullptr) continue;
      hand.push_back(&h->palm_body());
      for (int f = 0; f < kFingers; ++f) {
        for (int p = 0; p < kPhalanges; ++p) hand.push_back(&h->phalanx_body(f, p));
      }
    }
    for (auto& t : touching) t.assign(hand.size(), false);
  }

  ControlsState Read() {
    for (Control* c : {&wheel, &knob}) {
      if (!IsFinite(*c->body)) PutBack(*c);
    }
    GatherHands();
    ControlsState s;
    s.wheel_angle = WheelAngle();
    s.throttle = Throttle();
    const std::array<int, 2> contacts = HandContacts();
    s.wheel_contacts = contacts[0];
    s.throttle_contacts = contacts[1];
    s.wheel_held = s.wheel_contacts > 0;
    s.throttle_held = s.throttle_contacts > 0;
    return s;
  }

  void Apply(const ControlsActuation& a) {
    btGeneric6DofSpring2Constraint& w = *wheel.joint;
    const double torque = std::isfinite(a.wheel_torque) ? a.wheel_torque : 0.0;
    w.enableMotor(3, torque != 0.0);
    w.setMaxMotorForce(3, std::abs(torque));
    w.setTargetVelocity(3, torque > 0.0 ? kUnreachableSpeed : -kUnreachableSpeed);
    w.setStiffness(3, std::isfinite(a.wheel_spring) ? std::max(0.0, a.wheel_spring) : 0.0);

    btGeneric6DofSpring2Constraint& t = *knob.joint;
    const double travel = cockpit.throttle_travel;
    const double target =
        std::isfinite(a.throttle_target) ? std::clamp(a.throttle_target, -travel, travel) : 0.0;
    t.setStiffness(0, std::isfinite(a.throttle_spring) ? std::max(0.0, a.throttle_spring) : 0.0);
    t.setEquilibriumPoint(0, target);
    if (a.throttle_locked) {
      t.setLimit(0, target, target);
    } else if (locked) {
      t.setLimit(0, -travel, travel);
    }
    locked = a.throttle_locked;

    // A guidance with anything not finite, or not a unit normal, pushes nothing.
    const double n = std::hypot(a.guidance_normal_throttle, a.guidance_normal_rim);
    const bool usable = a.guidance_active && std::isfinite(a.guidance_throttle) &&
                        std::isfinite(a.guidance_wheel_angle) && std::abs(n - 1.0) < 1e-3 &&
                        std::isfinite(a.guidance_stiffness) && a.guidance_stiffness > 0.0 &&
                        std::isfinite(a.guidance_max_force) && a.guidance_max_force > 0.0;
    guidance = a;
    guidance.guidance_active = usable;
  }

  /// The guidance spring at the controls' positions, as impulses over `step_s`.
  /// Critically damped along its normal for the controls' own mass: a
  /// released lever or wheel comes back to the plane without being thrown
  /// past it (undamped, a lever let go at full forward against a 3 N push
  /// crossed its plane at speed and ended at full reverse). The sum stays
  /// within ±max: the spring only pushes back, and the damping only brakes
  /// (it holds a control back that springs out of the danger, as a hand would).
  void PushGuidance(double step_s) {
    guidance_force = 0.0;
    if (!guidance.guidance_active) return;
    const double r = cockpit.wheel_radius;
    const double nt = guidance.guidance_normal_throttle, nr = guidance.guidance_normal_rim;
    const double depth = (Throttle() - guidance.guidance_throttle) * nt +
                         (WheelAngle() - guidance.guidance_wheel_angle) * r * nr;
    if (!(depth > 0.0)) return;
    // Along the normal: the lever's speed, and the rim's towards the left
    // (the wheel angle grows with rotation about −x).
    const double speed =
        knob.body->getLinearVelocity().x() * nt - wheel.body->getAngularVelocity().x() * r * nr;
    const double mass =
        nt * nt * config.knob_mass + nr * nr * config.wheel_mass;  // the rim's: I / r² = m
    const double damping = 2.0 * std::sqrt(guidance.guidance_stiffness * mass);
    guidance_force = std::clamp(guidance.guidance_stiffness * depth + damping * speed,
                                -guidance.guidance_max_force, guidance.guidance_max_force);
    // Back along the normal: the lever along x; on the rim, a force f towards
    // the left is a torque f·r about −x (the wheel angle's axis).
    const double lever = -guidance_force * nt;
    const double rim_left = -guidance_force * nr;
    knob.body->applyCentralImpulse(btVector3(lever * step_s, 0, 0));
    wheel.body->applyTorqueImpulse(btVector3(-rim_left * r * step_s, 0, 0));
  }
};

CockpitControlsBody::CockpitControlsBody(PhysicsWorld& world, const CockpitConfig& cockpit,
                                         const ControlsBodyConfig& bodies)
    : impl_(std::make_unique<Impl>(world, cockpit, bodies)) {}
CockpitControlsBody::~CockpitControlsBody() = default;

ControlsState CockpitControlsBody::Read() { return impl_->Read(); }
void CockpitControlsBody::Apply(const ControlsActuation& actuation) { impl_->Apply(actuation); }
int CockpitControlsBody::resets() const { return impl_->resets; }
double CockpitControlsBody::guidance_force() const { return impl_->guidance_force; }
btRigidBody& CockpitControlsBody::wheel_body() { return *impl_->wheel.body; }
btRigidBody& CockpitControlsBody::throttle_body() { return *impl_->knob.body; }

ControlsLink::ControlsLink(PhysicsWorld& world, CockpitControlsBody& controls)
    : controls_(controls) {
  world.AddStepHook(*this);
}
void ControlsLink::BeforeStep() { controls_.Apply(actuation_.Load()); }
void ControlsLink::AfterStep() { state_.Store(controls_.Read()); }

}  // namespace haptel::physics
