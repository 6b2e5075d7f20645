#include "haptel/physics/proxy_hand.hpp"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>

#include "bullet_util.hpp"

// ---------------------------------------------------------------------------
// Which Bullet formulation, and why
//
// Every spring of the hand — the palm's 6-DoF coupling to the tracked wrist
// and the finger joints' drives to the glove angles — is one axis of a
// btGeneric6DofSpring2Constraint, solved by the sequential-impulse solver in
// the same pass as the contacts. Per axis, one of two formulations, chosen
// once from the axis's stiffness, damping and effective mass (MakeDrive):
//
// 1. Implicit ("soft lock"): the axis is LOCKED at its target (lower = upper
//    limit) and made compliant through its stop ERP and CFM — the
//    backward-Euler spring-damper of ODE / Box2D soft constraints, stable for
//    any stiffness. A row then obeys v⁺ = ERP·e/h − D·cfm·λ (D = J·M⁻¹·Jᵀ of
//    the row): Bullet applies a joint's CFM relative to the row's inverse mass
//    (m_jacDiagABInv is 1/D, the raw info2.cfm multiplies the accumulated
//    impulse). An implicit spring-damper wants λ = −h·(k·(e + h·v⁺) + c·v⁺),
//    so ERP = h·k/(h·k + c) and cfm = 1/(D·h·(h·k + c)), refreshed before
//    every step from the bodies' current inertia along the axis (PrepareStep).
//    The catch: with a joint's raw CFM the solver's update is successive
//    over-relaxation with factor 1 + cfm, which converges only for cfm < 1.
//    We use it where cfm ≤ 0.5, i.e. h·(h·k + c) ≥ 2·m_eff: the STIFF regime.
//    The finger joints are there (a 9 g distal phalanx has ~5e-7 kg·m²).
//
// 2. Bullet's own spring (enableSpring/setStiffness/setDamping): explicit —
//    the force k·e − c·v from the state at the start of the step bounds a
//    row — and clamped by Bullet (limitIfNeeded): k ≤ m/(16·h²) (ω·h ≤ 0.25)
//    and c ≤ m/h, for the lighter body's effective mass m. In the SOFT regime
//    where (1) would not converge it is comfortably stable and unclamped:
//    the palm coupling at 1 ms (ω·h ≈ 0.09 linear, ≈ 0.2 angular; the clamp
//    would start at 22 kN/m for a 350 g palm). Any axis whose parameters
//    reach the clamp is counted (ProxyHand::clamped_axes) rather than left to
//    be softened silently. The finger drives with this spring would be
//    clamped ~30× softer than asked: hence (1) for them.
//
// Not chosen: forces added by hand (explicit, and outside the solver, so
// contacts could not hold against them) and btMultiBody (a second body type
// for every contact with the scene).
// ---------------------------------------------------------------------------

namespace haptel::physics {
namespace {

constexpr int kBodies = 1 + kFingers * kPhalanges;
int BodyIndex(int finger, int phalanx) { return 1 + finger * kPhalanges + phalanx; }

/// Collision groups: each hand collides with everything but itself.
constexpr int kLeftHandGroup = 64;
constexpr int kRightHandGroup = 128;

/// A body's inverse effective mass along a rotation axis: axᵀ·I⁻¹·ax.
double InvInertiaAlong(const btRigidBody& body, const btVector3& axis) {
  return axis.dot(body.getInvInertiaTensorWorld() * axis);
}

/// Largest CFM the soft-lock formulation may use (SOR factor 1 + cfm < 2).
constexpr double kMaxCfm = 0.5;

/// One spring-damped axis of a 6-DoF constraint (0–2 linear, 3–5 angular).
struct Drive {
  btGeneric6DofSpring2Constraint* constraint = nullptr;
  int axis = 0;
  double stiffness = 0.0;
  double damping = 0.0;
  bool implicit = false;  ///< soft lock (1) or Bullet's spring (2)
  bool clamped = false;   ///< Bullet's spring limits the stiffness or damping asked for
  double target = 0.0;

  bool angular() const { return axis >= 3; }

  /// The row's current inverse effective mass D (frames at the bodies'
  /// centres of mass for linear rows).
  double InvMass() const {
    const btRigidBody& a = constraint->getRigidBodyA();
    const btRigidBody& b = constraint->getRigidBodyB();
    if (!angular()) return a.getInvMass() + b.getInvMass();
    const btVector3 ax = constraint->getAxis(axis - 3);
    return InvInertiaAlong(a, ax) + InvInertiaAlong(b, ax);
  }

  void SetTarget(double value) {
    target = value;
    if (implicit) {
      constraint->setLimit(axis, value, value);
    } else {
      constraint->setEquilibriumPoint(axis, value);
    }
  }

  /// Implicit rows: ERP and CFM for the bodies' current inertia. Call after
  /// the constraint's calculateTransforms().
  void Refresh(double h) {
    if (!implicit) return;
    const double inv_mass = InvMass();
    const double denom = h * stiffness + damping;
    if (denom <= 0.0 || inv_mass <= 0.0) return;
    constraint->setParam(BT_CONSTRAINT_STOP_ERP, h * stiffness / denom, axis);
    constraint->setParam(BT_CONSTRAINT_STOP_CFM, std::min(kMaxCfm, 1.0 / (inv_mass * h * denom)),
                         axis);
  }
};

/// Range of a body's inverse inertia over all axes (0 for a fixed body).
std::pair<double, double> InvInertiaRange(const btRigidBody& body) {
  const btVector3 d = body.getInvInertiaDiagLocal();
  return {std::min({d.x(), d.y(), d.z()}), std::max({d.x(), d.y(), d.z()})};
}

/// Picks the formulation of `drive` (see the note at the top) and sets it up.
Drive MakeDrive(btGeneric6DofSpring2Constraint& c, int axis, double stiffness, double damping,
                double h) {
  Drive d;
  d.constraint = &c;
  d.axis = axis;
  d.stiffness = stiffness;
  d.damping = damping;
  const btRigidBody& a = c.getRigidBodyA();
  const btRigidBody& b = c.getRigidBodyB();
  // Worst case over orientations: the smallest D gives the largest CFM.
  double d_min = a.getInvMass() + b.getInvMass();
  double bullet_mass = 1.0 / std::max(a.getInvMass(), b.getInvMass());  // Bullet: the lighter body
  if (d.angular()) {
    const auto ra = InvInertiaRange(a);
    const auto rb = InvInertiaRange(b);
    d_min = ra.first + rb.first;
    bullet_mass = 1.0 / std::max(ra.second, rb.second);
  }
  const double denom = h * stiffness + damping;
  d.implicit = denom > 0.0 && d_min > 0.0 && 1.0 / (d_min * h * denom) <= kMaxCfm;
  if (d.implicit) {
    c.enableSpring(axis, false);
  } else {
    c.setLimit(axis, 1.0, -1.0);  // free: the spring alone holds the axis
    c.enableSpring(axis, true);
    c.setStiffness(axis, stiffness, /*limitIfNeeded=*/true);
    c.setDamping(axis, damping, /*limitIfNeeded=*/true);
    d.clamped = std::sqrt(stiffness / bullet_mass) * h > 0.25 || damping * h > bullet_mass;
  }
  d.SetTarget(0.0);
  return d;
}

btMatrix3x3 RotX(double a) { return btMatrix3x3(btQuaternion(btVector3(1, 0, 0), a)); }
btMatrix3x3 RotY(double a) { return btMatrix3x3(btQuaternion(btVector3(0, 1, 0), a)); }
btMatrix3x3 RotZ(double a) { return btMatrix3x3(btQuaternion(btVector3(0, 0, 1), a)); }

}  // namespace

struct ProxyHand::Impl {
  struct Joint {
    std::unique_ptr<btGeneric6DofSpring2Constraint> constraint;
    btTransform frame_in_parent;
    btTransform frame_in_child;
    bool abduction = false;  ///< joint 0: abduction is driven too (else locked)
    double flexion_target = 0.0;
    double abduction_target = 0.0;
    Drive flexion_drive;
    Drive abduction_drive;
  };

  btDiscreteDynamicsWorld& world;
  ProxyHandConfig config;
  double h;
  Side side;
  double mirror;  ///< +1 right hand, −1 left hand (y of the hand frame)

  std::unique_ptr<btBoxShape> palm_shape;
  std::array<std::unique_ptr<btCapsuleShapeX>, kPhalanges> phalanx_shapes;
  std::unique_ptr<btSphereShape> anchor_shape;
  std::array<std::unique_ptr<btRigidBody>, kBodies> bodies;  ///< palm, then finger by finger
  std::array<btTransform, kBodies> rest;  ///< bodies in the hand frame, fingers straight
  std::unique_ptr<btRigidBody> anchor;    ///< kinematic: the tracked palm
  std::unique_ptr<btGeneric6DofSpring2Constraint> coupling;
  std::array<Drive, 6> coupling_drives;
  int clamped_axes = 0;
  std::array<Joint, kFingers * kPhalanges> joints;  ///< joint j of finger f: [f·3 + j]

  bool placed = false;
  btTransform tracked_wrist = btTransform::getIdentity();
  std::array<btTransform, kBodies> tracked;  ///< every body of the tracked hand, world frame

  Impl(btDiscreteDynamicsWorld& w, const ProxyHandConfig& c, double step_s, Side s)
      : world(w), config(c), h(step_s), side(s), mirror(s == Side::kRight ? 1.0 : -1.0) {
    Build();
    ComputeTracked();
    Reset();
  }

  ~Impl() {
    for (Joint& j : joints) world.removeConstraint(j.constraint.get());
    world.removeConstraint(coupling.get());
    for (auto& b : bodies) world.removeRigidBody(b.get());
    world.removeRigidBody(anchor.get());
  }

  btTransform PalmInHand() const {
    return btTransform(btMatrix3x3::getIdentity(), btVector3(config.palm_half_extents[0], 0, 0));
  }

  void Build() {
    const auto& he = config.palm_half_extents;
    const double r = config.phalanx_radius;
    palm_shape = std::make_unique<btBoxShape>(btVector3(he[0], he[1], he[2]));
    palm_shape->setMargin(BoxMargin(he));
    for (int p = 0; p < kPhalanges; ++p) {
      phalanx_shapes[p] =
          std::make_unique<btCapsuleShapeX>(r, std::max(config.phalanx_length[p] - 2.0 * r, 1e-4));
    }
    anchor_shape = std::make_unique<btSphereShape>(0.001);

    const int group = side == Side::kRight ? kRightHandGroup : kLeftHandGroup;
    const int mask = btBroadphaseProxy::AllFilter & ~group;
    auto make_body = [&](btCollisionShape* shape, double mass, const btTransform& pose) {
      btVector3 inertia(0, 0, 0);
      shape->calculateLocalInertia(mass, inertia);
      btRigidBody::btRigidBodyConstructionInfo info(mass, nullptr, shape, inertia);
      info.m_startWorldTransform = pose;
      auto body = std::make_unique<btRigidBody>(info);
      SetMaterial(*body, config.material);
      body->setActivationState(DISABLE_DEACTIVATION);  // the hand is never asleep
      if (!config.gravity) body->setFlags(body->getFlags() | BT_DISABLE_WORLD_GRAVITY);
      world.addRigidBody(body.get(), group, mask);
      if (!config.gravity) body->setGravity(btVector3(0, 0, 0));
      return body;
    };

    // Rest pose in the hand frame: fingers straight along x.
    rest[0] = PalmInHand();
    bodies[0] = make_body(palm_shape.get(), config.palm_mass, rest[0]);
    const double palm_front = 2.0 * he[0];
    const std::array<double, 4> finger_y{0.675, 0.225, -0.225, -0.675};
    for (int f = 0; f < kFingers; ++f) {
      btVector3 base;
      double splay = 0.0;
      if (f == kThumb) {
        base = btVector3(0.3 * palm_front, mirror * he[1], 0);
        splay = mirror * 0.35;  // rad, the thumb's rest direction towards its side
      } else {
        base = btVector3(palm_front, mirror * he[1] * finger_y[f - 1], 0);
      }
      const btMatrix3x3 basis = RotZ(splay);
      const btVector3 dir = basis.getColumn(0);
      btVector3 joint_point = base;
      for (int p = 0; p < kPhalanges; ++p) {
        const double length = config.phalanx_length[p];
        const int i = BodyIndex(f, p);
        rest[i] = btTransform(basis, joint_point + dir * (0.5 * length));
        bodies[i] = make_body(phalanx_shapes[p].get(), config.phalanx_mass[p], rest[i]);
        // Joint frame: x = flexion axis (the phalanx's y), y = abduction axis
        // (its z), z = its long axis; Bullet's XYZ Euler order keeps the
        // flexion on the first axis, whose range is the full ±π.
        btMatrix3x3 frame_basis;
        frame_basis.setValue(basis[0][1], basis[0][2], basis[0][0],  //
                             basis[1][1], basis[1][2], basis[1][0],  //
                             basis[2][1], basis[2][2], basis[2][0]);
        const btTransform frame(frame_basis, joint_point);
        const int parent = p == 0 ? 0 : BodyIndex(f, p - 1);
        Joint& joint = joints[f * kPhalanges + p];
        joint.frame_in_parent = rest[parent].inverse() * frame;
        joint.frame_in_child = rest[i].inverse() * frame;
        joint.abduction = p == 0;
        joint.constraint = std::make_unique<btGeneric6DofSpring2Constraint>(
            *bodies[parent], *bodies[i], joint.frame_in_parent, joint.frame_in_child, RO_XYZ);
        joint.constraint->setLinearLowerLimit(btVector3(0, 0, 0));
        joint.constraint->setLinearUpperLimit(btVector3(0, 0, 0));
        joint.constraint->setAngularLowerLimit(btVector3(0, 0, 0));
        joint.constraint->setAngularUpperLimit(btVector3(0, 0, 0));
        joint.flexion_drive =
            MakeDrive(*joint.constraint, 3, config.joint_stiffness, config.joint_damping, h);
        clamped_axes += joint.flexion_drive.clamped ? 1 : 0;
        if (joint.abduction) {
          joint.abduction_drive =
              MakeDrive(*joint.constraint, 4, config.joint_stiffness, config.joint_damping, h);
          clamped_axes += joint.abduction_drive.clamped ? 1 : 0;
        }
        world.addConstraint(joint.constraint.get(), /*disableCollisionsBetweenLinkedBodies=*/true);
        joint_point += dir * length;
      }
    }

    // The tracked palm: a kinematic body that collides with nothing; Bullet
    // derives its velocity from its pose change, so the coupling damps the
    // proxy's motion relative to the tracked hand, not to the world.
    btRigidBody::btRigidBodyConstructionInfo info(0.0, nullptr, anchor_shape.get());
    info.m_startWorldTransform = rest[0];
    anchor = std::make_unique<btRigidBody>(info);
    anchor->setCollisionFlags(anchor->getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    anchor->setActivationState(DISABLE_DEACTIVATION);
    world.addRigidBody(anchor.get(), 0, 0);
    // Both coupling frames sit at the palm's centre of mass: the linear rows
    // then act on the palm's mass alone (D = 1/m) and do not twist it.
    coupling = std::make_unique<btGeneric6DofSpring2Constraint>(
        *anchor, *bodies[0], btTransform::getIdentity(), btTransform::getIdentity(), RO_XYZ);
    coupling->setLinearLowerLimit(btVector3(0, 0, 0));
    coupling->setLinearUpperLimit(btVector3(0, 0, 0));
    coupling->setAngularLowerLimit(btVector3(0, 0, 0));
    coupling->setAngularUpperLimit(btVector3(0, 0, 0));
    for (int axis = 0; axis < 6; ++axis) {
      const bool linear = axis < 3;
      coupling_drives[axis] =
          MakeDrive(*coupling, axis,
                    linear ? config.coupling_linear_stiffness : config.coupling_angular_stiffness,
                    linear ? config.coupling_linear_damping : config.coupling_angular_damping, h);
      clamped_axes += coupling_drives[axis].clamped ? 1 : 0;
    }
    world.addConstraint(coupling.get(), true);
  }

  /// Joint targets from the glove (haptics/calibration.hpp, kGloveSensorNames).
  void SetTargets(const std::array<double, haptics::kGloveJoints>& a) {
    auto set = [&](int f, int p, double flexion, double abduction) {
      Joint& j = joints[f * kPhalanges + p];
      j.flexion_target = flexion;
      j.abduction_target = mirror * abduction;
    };
    set(kThumb, 0, a[0], a[3]);  // thumb roll drives the base flexion, thumb abduction its spread
    set(kThumb, 1, a[1], 0.0);
    set(kThumb, 2, a[2], 0.0);
    // Abduction: the index spreads towards the thumb, ring and pinky away.
    const std::array<double, 4> spread{a[16], 0.0, -a[17], -(a[17] + a[18])};
    for (int f = kIndex; f <= kPinky; ++f) {
      const int s = 4 + 3 * (f - kIndex);
      set(f, 0, a[s], spread[f - kIndex]);
      set(f, 1, a[s + 1], 0.0);
      set(f, 2, a[s + 2], 0.0);
    }
    // palm_arch, wrist_pitch and wrist_yaw have no proxy joint: the wrist
    // pose comes from the tracker.
    // Bullet reports the relative rotation frameA⁻¹·frameB = Rz(−c)·Ry(−b)·Rx(−a)
    // for its XYZ angles (a, b, c) (matrixToEulerXYZ reads the matrix
    // column-major), so its angles are the opposites of ours.
    for (Joint& j : joints) {
      j.flexion_drive.SetTarget(-j.flexion_target);
      if (j.abduction) j.abduction_drive.SetTarget(-j.abduction_target);
    }
  }

  /// Forward kinematics of the tracked hand with the proxy's own joint model:
  /// child = parent · frame_in_parent · Ry(abduction)·Rx(flexion) · frame_in_child⁻¹
  /// (Bullet's RO_XYZ relative rotation, see SetTargets), so an unobstructed
  /// proxy settles exactly on it.
  void ComputeTracked() {
    tracked[0] = tracked_wrist * rest[0];
    for (int f = 0; f < kFingers; ++f) {
      for (int p = 0; p < kPhalanges; ++p) {
        const Joint& j = joints[f * kPhalanges + p];
        const int parent = p == 0 ? 0 : BodyIndex(f, p - 1);
        const double abd = j.abduction ? j.abduction_target : 0.0;
        const btTransform rotation(RotY(abd) * RotX(j.flexion_target), btVector3(0, 0, 0));
        tracked[BodyIndex(f, p)] =
            tracked[parent] * j.frame_in_parent * rotation * j.frame_in_child.inverse();
      }
    }
  }

  bool SetTracked(const haptics::HandSample& s) {
    if (!s.valid) return false;
    for (double v : s.position) {
      if (!std::isfinite(v)) return false;
    }
    for (double v : s.orientation) {
      if (!std::isfinite(v)) return false;
    }
    for (double v : s.finger_angles) {
      if (!std::isfinite(v)) return false;
    }
    btQuaternion q(s.orientation[1], s.orientation[2], s.orientation[3], s.orientation[0]);
    if (q.length2() < 1e-12) return false;
    q.normalize();
    const btTransform wanted(q, btVector3(s.position[0], s.position[1], s.position[2]));
    tracked_wrist = placed ? Followed(wanted) : wanted;
    SetTargets(s.finger_angles);
    ComputeTracked();
    anchor->setWorldTransform(tracked[0]);  // its velocity follows at the next step
    if (!placed) {
      placed = true;
      Reset();
    }
    return true;
  }

  /// The tracked wrist moved towards `wanted` by at most a hand's top speed
  /// over one step (ProxyHand::kMaxFollowSpeed_mps, kMaxFollowTurn_radps).
  /// The anchor is kinematic: Bullet gives it the velocity of its motion over
  /// the step, so a sample that leapt while the physics thread was held up
  /// (a loaded machine: a step late by a second, the hand moved on) would
  /// otherwise drive the coupling's damping at metres a millisecond and fling
  /// the hand off what it holds. Late steps make the hand catch up at a
  /// hand's speed instead: the simulation slower, nothing dropped.
  btTransform Followed(const btTransform& wanted) const {
    const btVector3 from = tracked_wrist.getOrigin();
    btVector3 move = wanted.getOrigin() - from;
    const double reach = ProxyHand::kMaxFollowSpeed_mps * h;
    if (move.length() > reach) move *= reach / move.length();
    const btQuaternion q0 = tracked_wrist.getRotation();
    btQuaternion q1 = wanted.getRotation();
    const double turn = q0.angleShortestPath(q1);
    const double turn_reach = ProxyHand::kMaxFollowTurn_radps * h;
    if (turn > turn_reach) q1 = q0.slerp(q1, turn_reach / turn);
    return btTransform(q1, from + move);
  }

  void Place(btRigidBody& body, const btTransform& pose) {
    body.setWorldTransform(pose);
    body.setInterpolationWorldTransform(pose);
    body.setLinearVelocity(btVector3(0, 0, 0));
    body.setAngularVelocity(btVector3(0, 0, 0));
    body.setInterpolationLinearVelocity(btVector3(0, 0, 0));
    body.setInterpolationAngularVelocity(btVector3(0, 0, 0));
    body.clearForces();
    body.updateInertiaTensor();
    ForgetContacts(world, body);
  }

  void Reset() {
    for (int i = 0; i < kBodies; ++i) {
      Place(*bodies[i], tracked[i]);
      bodies[i]->forceActivationState(DISABLE_DEACTIVATION);
    }
    Place(*anchor, tracked[0]);
  }

  void PrepareStep() {
    coupling->calculateTransforms();
    for (Drive& d : coupling_drives) d.Refresh(h);
    for (Joint& j : joints) {
      j.constraint->calculateTransforms();
      j.flexion_drive.Refresh(h);
      if (j.abduction) j.abduction_drive.Refresh(h);
    }
  }

  bool Finite() const {
    for (const auto& b : bodies) {
      if (!IsFinite(*b)) return false;
    }
    return true;
  }

  btTransform WristOf(const btTransform& palm) const { return palm * rest[0].inverse(); }
  btVector3 TipOf(const btTransform& distal) const {
    return distal * btVector3(0.5 * config.phalanx_length[2], 0, 0);
  }
  btVector3 ProxyTip(int f) const { return TipOf(bodies[BodyIndex(f, 2)]->getWorldTransform()); }
  btVector3 TrackedTip(int f) const { return TipOf(tracked[BodyIndex(f, 2)]); }
  btVector3 TrackedNail(int f) const { return tracked[BodyIndex(f, 2)].getBasis().getColumn(2); }

  std::array<double, kFingers> FingerForces() const {
    std::array<double, kFingers> out{};
    // In each hand's own palm frame: the grasp strings pull a finger against
    // the back of the hand, and the wrist's error is the wrist force's job.
    const btTransform proxy_palm = bodies[0]->getWorldTransform().inverse();
    const btTransform tracked_palm = tracked[0].inverse();
    for (int f = 0; f < kFingers; ++f) {
      const btVector3 proxy_tip = proxy_palm * ProxyTip(f);
      const btVector3 tracked_tip = tracked_palm * TrackedTip(f);
      const btVector3 nail = tracked_palm.getBasis() * TrackedNail(f);
      // Unilateral: only when the proxy is held back on the nail side of
      // where the operator's finger is, i.e. something is in its way.
      const double e = (proxy_tip - tracked_tip).dot(nail);
      out[f] = config.finger_feedback_stiffness * std::max(0.0, e);
    }
    return out;
  }
};

ProxyHand::ProxyHand(btDiscreteDynamicsWorld& world, const ProxyHandConfig& config, double step_s,
                     Side side)
    : impl_(std::make_unique<Impl>(world, config, step_s, side)) {}
ProxyHand::~ProxyHand() = default;

Side ProxyHand::side() const { return impl_->side; }
bool ProxyHand::SetTracked(const haptics::HandSample& tracked) {
  return impl_->SetTracked(tracked);
}
bool ProxyHand::placed() const { return impl_->placed; }
void ProxyHand::Reset() { impl_->Reset(); }
void ProxyHand::PrepareStep() { impl_->PrepareStep(); }
int ProxyHand::clamped_axes() const { return impl_->clamped_axes; }
bool ProxyHand::Finite() const { return impl_->Finite(); }

Pose ProxyHand::ProxyWrist() const {
  return ToPose(impl_->WristOf(impl_->bodies[0]->getWorldTransform()));
}
Pose ProxyHand::TrackedWrist() const { return ToPose(impl_->tracked_wrist); }
Pose ProxyHand::Phalanx(int finger, int phalanx) const {
  return ToPose(impl_->bodies[BodyIndex(finger, phalanx)]->getWorldTransform());
}
Vec3d ProxyHand::ProxyTip(int finger) const { return ToVec(impl_->ProxyTip(finger)); }
Vec3d ProxyHand::TrackedTip(int finger) const { return ToVec(impl_->TrackedTip(finger)); }
Vec3d ProxyHand::TrackedNailNormal(int finger) const { return ToVec(impl_->TrackedNail(finger)); }

double ProxyHand::FlexionAngle(int finger, int joint) const {
  btGeneric6DofSpring2Constraint& c = *impl_->joints[finger * kPhalanges + joint].constraint;
  c.calculateTransforms();
  return -c.getAngle(0);  // Bullet's sign is the opposite (see SetTargets)
}

std::array<double, kFingers> ProxyHand::FingerForces() const { return impl_->FingerForces(); }

void ProxyHand::FillSetpoint(haptics::ForceSetpoint& sp) const {
  const Pose wrist = ProxyWrist();
  sp.coupling_enabled = true;
  sp.coupling_target = wrist.position;
  sp.coupling_stiffness = impl_->config.feedback_stiffness;
  sp.coupling_damping = impl_->config.feedback_damping;
  sp.finger_forces = FingerForces();
}

HandPoses ProxyHand::Snapshot(int64_t t_ns) const {
  HandPoses out;
  out.t_ns = t_ns;
  out.valid = impl_->placed;
  out.proxy_wrist = ProxyWrist();
  out.tracked_wrist = TrackedWrist();
  for (int f = 0; f < kFingers; ++f) {
    for (int p = 0; p < kPhalanges; ++p) out.phalanges[f][p] = Phalanx(f, p);
    out.proxy_tips[f] = ProxyTip(f);
    out.tracked_tips[f] = TrackedTip(f);
  }
  out.finger_forces = FingerForces();
  return out;
}

btRigidBody& ProxyHand::palm_body() { return *impl_->bodies[0]; }
btRigidBody& ProxyHand::phalanx_body(int finger, int phalanx) {
  return *impl_->bodies[BodyIndex(finger, phalanx)];
}

}  // namespace haptel::physics
