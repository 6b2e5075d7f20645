#pragma once
/// @file The proxy ("mass-spring") hand of one side: rigid bodies that follow
/// the tracked hand through springs, collide with the world, and cannot
/// penetrate it (DESIGN.md, "Proxy hand").
///
/// Bodies: a palm box and, per finger (thumb, index, middle, ring, pinky),
/// three capsules — metacarpal, proximal, distal. Finger joints are driven
/// towards the tracked glove angles; the palm is coupled to the tracked wrist
/// pose by a 3-DoF linear and a 3-DoF angular spring-damper.
///
/// Hand frame: origin at the wrist, x along the fingers, y towards the thumb of
/// a right hand, z out of the back of the hand (the palm faces −z, the nails
/// +z). The left hand is the mirror image (its thumb is on −y).
///
/// A ProxyHand belongs to a PhysicsWorld and is used only from the thread that
/// steps that world; other threads read its HandPoses through the world.
#include <array>
#include <cstdint>
#include <memory>

#include "haptel/config/physics.hpp"
#include "haptel/haptics/types.hpp"

class btDiscreteDynamicsWorld;
class btRigidBody;

namespace haptel::physics {

using haptics::Side;
using haptics::Vec3d;

/// A rigid pose: position (m) and unit quaternion (w, x, y, z), like HandSample.
struct Pose {
  Vec3d position{};
  std::array<double, 4> orientation{1, 0, 0, 0};
};

enum Finger : int { kThumb = 0, kIndex = 1, kMiddle = 2, kRing = 3, kPinky = 4 };
constexpr int kFingers = haptics::kFingers;
/// Phalanges per finger: metacarpal, proximal, distal.
constexpr int kPhalanges = 3;

/// Everything a slower thread (view, recorder) wants of one hand, in one
/// trivially copyable value for a seqlock.
struct HandPoses {
  int64_t t_ns = 0;
  bool valid = false;  ///< the hand has been placed at a tracked pose
  Pose proxy_wrist;
  Pose tracked_wrist;
  std::array<std::array<Pose, kPhalanges>, kFingers>
      phalanges{};  ///< proxy bodies (the visual hand)
  std::array<Vec3d, kFingers> proxy_tips{};
  std::array<Vec3d, kFingers> tracked_tips{};
  std::array<double, kFingers> finger_forces{};  ///< N, what the servo loop is asked for
};

class ProxyHand {
 public:
  /// m/s and rad/s: how fast the tracked wrist the proxy follows may move, a
  /// quick hand's top speed. A sample beyond it (the physics thread stepped
  /// late, the device's hand went on) is followed at it, over the next steps.
  static constexpr double kMaxFollowSpeed_mps = 3.0;
  static constexpr double kMaxFollowTurn_radps = 30.0;

  /// Builds the bodies and joints in `world` (which must outlive the hand),
  /// at rest at the origin; the first SetTracked puts the hand on the tracked pose.
  ProxyHand(btDiscreteDynamicsWorld& world, const ProxyHandConfig& config, double step_s,
            Side side);
  ~ProxyHand();
  ProxyHand(const ProxyHand&) = delete;
  ProxyHand& operator=(const ProxyHand&) = delete;

  Side side() const;
  /// The tracked hand: the coupling's target (wrist pose) and the joint
  /// drives' targets (glove angles). The first call places the whole hand
  /// there; later ones move the target towards the sample at most at
  /// kMaxFollowSpeed_mps / kMaxFollowTurn_radps for one step (call once a step).
  /// Ignores (returns false) a sample that is not valid or not finite.
  bool SetTracked(const haptics::HandSample& tracked);
  /// True once a tracked sample placed the hand.
  bool placed() const;
  /// Puts every body on the tracked hand's pose, at rest (NaN recovery).
  void Reset();
  /// Refreshes the implicit springs' solver parameters; before every step.
  void PrepareStep();
  /// Spring axes whose stiffness or damping Bullet's own spring clamps (see
  /// proxy_hand.cpp on the formulations); 0 means the hand is as stiff as configured.
  int clamped_axes() const;
  /// False when any body's pose or velocity is NaN or infinite.
  bool Finite() const;

  Pose ProxyWrist() const;
  Pose TrackedWrist() const;
  Pose Phalanx(int finger, int phalanx) const;
  Vec3d ProxyTip(int finger) const;
  Vec3d TrackedTip(int finger) const;
  /// Unit normal out of the tracked distal phalanx's nail.
  Vec3d TrackedNailNormal(int finger) const;
  /// Proxy joint angle (rad) about the flexion axis; joint 0 is at the palm.
  double FlexionAngle(int finger, int joint) const;
  /// Unilateral finger forces: k_f·max(0, (proxy − tracked tip)·nail normal),
  /// N, with each tip taken in its own hand's palm frame (the wrist's error is
  /// rendered by the wrist force, not by every finger).
  std::array<double, kFingers> FingerForces() const;
  /// Writes the proxy coupling (target = proxy wrist, feedback stiffness and
  /// damping) and the finger forces into `setpoint`, keeping its other fields.
  void FillSetpoint(haptics::ForceSetpoint& setpoint) const;
  HandPoses Snapshot(int64_t t_ns) const;

  /// The Bullet bodies, for scenes and tests (e.g. to inject a fault).
  btRigidBody& palm_body();
  btRigidBody& phalanx_body(int finger, int phalanx);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::physics
