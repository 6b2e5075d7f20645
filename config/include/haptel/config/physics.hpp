#pragma once
/// @file The physics thread's configuration (config/physics.yaml): the fixed
/// step, the solver, gravity, and the proxy ("mass-spring") hands — their
/// bodies, the glove-driven joint drives, the wrist coupling to the tracked
/// hand, and the force feedback the servo loop is asked to render.
///
/// Units are SI: m, kg, s, N, rad (stiffness N/m or N·m/rad, damping
/// N·s/m or N·m·s/rad).
#include <array>
#include <filesystem>

#include "haptel/config/archive.hpp"

namespace haptel {

/// Surface of a body: Bullet has one friction coefficient (static = dynamic);
/// pairs combine by the average (DESIGN.md, "Haptic scene").
///
/// Rolling and spinning friction are lever arms (m): a contact carrying the
/// normal force N resists rolling (about the tangent axes) and spinning (about
/// the normal) with a torque of at most lever·N. They stand for what a rigid
/// point contact lacks: the contact patch of a soft surface such as a finger
/// pad. A pair's lever is the sum of the two bodies' (each soft surface
/// shifts the pressure centre by its own; a rigid one adds nothing). Bullet
/// solves spinning friction only on contacts that also have rolling friction.
struct PhysicsMaterial {
  double friction = 0.8;
  double restitution = 0.0;
  double rolling_friction = 0.0;   ///< m
  double spinning_friction = 0.0;  ///< m

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(friction), config::Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(restitution), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(rolling_friction), config::Range{0.0, 0.05});
    a->Visit(HAPTEL_NVP(spinning_friction), config::Range{0.0, 0.05});
  }

  /// Throws ConfigFieldError unless every value is in range and spinning
  /// friction comes with rolling friction (Bullet ignores it otherwise).
  void ValidateOrThrow() const;
};

/// One proxy hand (both sides alike; the left one is the mirror image).
/// Hand frame: origin at the wrist, x along the fingers, y towards the thumb
/// of a right hand, z out of the back of the hand (palm faces −z).
struct ProxyHandConfig {
  double palm_mass = 0.350;                                      ///< kg
  std::array<double, 3> palm_half_extents{0.045, 0.040, 0.012};  ///< m
  /// Per finger, from the palm out: metacarpal, proximal, distal.
  std::array<double, 3> phalanx_mass{0.013, 0.010, 0.009};    ///< kg
  std::array<double, 3> phalanx_length{0.045, 0.027, 0.022};  ///< m, joint to joint
  double phalanx_radius = 0.008;                              ///< m (capsules)
  /// Joint drives pulling every finger joint to the tracked glove angle.
  double joint_stiffness = 1.0;  ///< N·m/rad
  double joint_damping = 0.005;  ///< N·m·s/rad
  /// Palm to tracked wrist: 3-DoF linear and 3-DoF angular spring-dampers.
  double coupling_linear_stiffness = 3000.0;  ///< N/m
  double coupling_linear_damping = 40.0;      ///< N·s/m
  double coupling_angular_stiffness = 10.0;   ///< N·m/rad
  double coupling_angular_damping = 0.1;      ///< N·m·s/rad
  /// What the servo loop renders: wrist F = k·(proxy − tracked) − b·v, and per
  /// finger F = k_f·max(0, (proxy − tracked tip)·nail normal).
  double feedback_stiffness = 1000.0;        ///< N/m
  double feedback_damping = 5.0;             ///< N·s/m
  double finger_feedback_stiffness = 300.0;  ///< N/m
  /// The operator's own hand is weightless to him: by default the proxy is too.
  bool gravity = false;
  /// The finger pads and the palm. Rolling friction: Bullet caches a
  /// capsule's contact points on the capsule, so while it rolls they turn
  /// with it and trail its axis (they are dropped only 0.3–0.5 mm out, the
  /// manifold's breaking threshold); those still touching carry the normal
  /// force behind the axis — at most √(2·r·d) for a penetration d, 0.2–0.6 mm
  /// for the 2–20 µm of a resting or pressed fingertip — and drive the roll
  /// on. A 1 mm lever outweighs that and is small beside a pressed finger
  /// pad's contact patch (a radius of several millimetres).
  /// Spinning friction: a Hertzian patch of radius a transmits at most
  /// (3π/16)·μ·a·N about its normal, ≈ 2.4 mm·N for μ = 1, a = 4 mm.
  PhysicsMaterial material{1.0, 0.0, 0.001, 0.002};

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(palm_mass), Range{0.01, 10.0});
    a->Visit(HAPTEL_NVP(palm_half_extents), Range{0.002, 0.5});
    a->Visit(HAPTEL_NVP(phalanx_mass), Range{0.001, 1.0});
    a->Visit(HAPTEL_NVP(phalanx_length), Range{0.005, 0.2});
    a->Visit(HAPTEL_NVP(phalanx_radius), Range{0.001, 0.05});
    a->Visit(HAPTEL_NVP(joint_stiffness), Range{1e-4, 1e4});
    a->Visit(HAPTEL_NVP(joint_damping), Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(coupling_linear_stiffness), Range{1.0, 1e8});
    a->Visit(HAPTEL_NVP(coupling_linear_damping), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(coupling_angular_stiffness), Range{1e-3, 1e5});
    a->Visit(HAPTEL_NVP(coupling_angular_damping), Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(feedback_stiffness), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(feedback_damping), Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(finger_feedback_stiffness), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(gravity));
    a->Visit(HAPTEL_NVP(material));
  }

  /// Throws ConfigFieldError unless every value is in range (the material's
  /// too) and every phalanx_length >= 2 * phalanx_radius.
  void ValidateOrThrow() const;
};

struct PhysicsConfig {
  std::filesystem::path file;
  double step_s = 0.001;  ///< fixed step of the physics thread
  int solver_iterations = 20;
  std::array<double, 3> gravity{0.0, 0.0, -9.81};  ///< m/s², device frame
  int realtime_priority = 0;  ///< SCHED_FIFO priority for the thread (0: do not ask)
  ProxyHandConfig hand;
  /// An offline reference run: a world its caller steps by hand to compute a
  /// ground truth (the work-precision benchmark's 0.025 ms reference run),
  /// never a physics thread. Set by code only; physics files have no such
  /// key. It lets step_s go below what a thread may ask (kMinStepS) down to
  /// kMinReferenceStepS; every other rule stays.
  bool reference = false;

  /// The step a physics thread, and so a physics file, may ask for: 0.1 ms
  /// (10 kHz, ten times the servo rate) to 10 ms.
  static constexpr double kMinStepS = 1e-4;
  static constexpr double kMaxStepS = 0.01;
  /// The finest step of a reference run (1 µs): finer than any ground truth
  /// needs, coarse enough that a step of 0 or a typo in the exponent is caught.
  static constexpr double kMinReferenceStepS = 1e-6;

  template <typename Archive>
  void Serialize(Archive* a) {
    // Every field but `file` and `reference` (the program's); step_s's range
    // depends on `reference`: ValidateOrThrow.
    a->Visit(HAPTEL_NVP(step_s));
    a->Visit(HAPTEL_NVP(solver_iterations), config::Range{1, 1000});
    a->Visit(HAPTEL_NVP(gravity), config::Range{-100.0, 100.0});
    a->Visit(HAPTEL_NVP(realtime_priority), config::Range{0, 99});
    a->Visit(HAPTEL_NVP(hand));
  }

  /// Throws ConfigFieldError unless the step (in [kMinStepS, kMaxStepS], or
  /// from kMinReferenceStepS for a reference), solver, gravity and priority
  /// are in range and the hand is valid (keys "hand.*").
  void ValidateOrThrow() const;
};

/// Loads and validates (PhysicsConfig::ValidateOrThrow) a physics file
/// (strict: unknown keys and out-of-range values are errors naming file,
/// line, key and the expected value).
PhysicsConfig LoadPhysics(const std::filesystem::path& file);

}  // namespace haptel
