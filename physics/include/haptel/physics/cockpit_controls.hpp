#pragma once
/// @file The physical controls of the cockpit interfaces: a steering wheel on
/// a hinge and a throttle lever on a slider, as Bullet bodies the proxy hands
/// touch, push and grasp (config/interfaces/cockpit*.yaml).
///
/// Device frame (x forward, y left, z up). The wheel is a rim of radius
/// `wheel_radius` in the y–z plane, centred on `wheel_hub`, turning about the
/// hinge axis −x (pointing at the driver): a positive angle is a turn to the
/// left (counter-clockwise seen by the driver), limited to ±wheel_max_angle.
/// The throttle is a knob sliding along x through `throttle_centre`, positive
/// forward, limited to ±throttle_travel.
///
/// Physics does not depend on interfaces: Read and Apply use the plain
/// structs below, field for field the interfaces' CockpitControls and
/// ControlActuation (cockpit_logic.hpp); the interface layer translates.
///
/// The controls live in a PhysicsWorld that must outlive them, and are used
/// only from the thread that steps it. Build them before the world's Start.
#include <array>
#include <memory>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/physics/world.hpp"

class btRigidBody;

namespace haptel::physics {

/// What the controls report (interfaces::CockpitControls, plus contact counts).
struct ControlsState {
  double wheel_angle = 0.0;    ///< rad, + = turned left
  double throttle = 0.0;       ///< m from centre, + = forward
  bool wheel_held = false;     ///< a proxy hand body touches the rim
  bool throttle_held = false;  ///< a proxy hand body touches the knob
  int wheel_contacts = 0;      ///< hand bodies touching the rim (palm, phalanges; both hands)
  int throttle_contacts = 0;   ///< hand bodies touching the knob
};

/// What the controls must feel (interfaces::ControlActuation). Kept until the
/// next Apply: the world may step several times between two calls.
struct ControlsActuation {
  double wheel_torque = 0.0;     ///< N·m about the hinge, + = toward left
  double wheel_spring = 0.0;     ///< N·m/rad toward angle 0
  double throttle_spring = 0.0;  ///< N/m toward throttle_target
  double throttle_target = 0.0;  ///< m
  bool throttle_locked = false;  ///< hold the lever at throttle_target rigidly
  /// Shared control's guidance (cockpit-shared): a spring past a plane in the
  /// controls' space (lever m, rim arc = angle × wheel radius m), saturating
  /// at guidance_max_force, pushing the lever along x and turning the wheel,
  /// evaluated at every step from the controls' positions, and critically
  /// damped along its normal for the controls' own mass (a released control
  /// comes back to the plane, not past it).
  bool guidance_active = false;
  double guidance_throttle = 0.0;         ///< m: the plane's point, lever
  double guidance_wheel_angle = 0.0;      ///< rad: the plane's point, wheel
  double guidance_normal_throttle = 1.0;  ///< unit normal towards the danger: lever part
  double guidance_normal_rim = 0.0;       ///< ...rim part (+ = turned left)
  double guidance_stiffness = 0.0;        ///< N/m
  double guidance_max_force = 0.0;        ///< N
};

/// Bodies of the controls (beyond the positions in CockpitConfig).
struct ControlsBodyConfig {
  double wheel_mass = 0.3;      ///< kg, the rim
  double rim_radius = 0.012;    ///< m, half the rim's thickness
  int rim_segments = 16;        ///< capsules approximating the torus
  double wheel_damping = 0.02;  ///< N·m·s/rad, steering column
  double knob_mass = 0.1;       ///< kg
  /// m: a bar along the lever's travel (x), grasped like the wheel's rim
  std::array<double, 3> knob_half_extents{0.04, 0.012, 0.012};
  double throttle_damping = 1.0;       ///< N·s/m
  PhysicsMaterial material{1.0, 0.0};  ///< rubbery: fingers grip it
  double contact_distance = 0.002;     ///< m, a manifold point this close counts as touching

  /// Throws ConfigFieldError unless masses, radii and extents are finite and
  /// > 0, dampings >= 0, rim_segments in [6, 1000] and the material is valid.
  void ValidateOrThrow() const;
};

class CockpitControlsBody {
 public:
  /// Adds the wheel, the lever and their joints to `world` (the world's
  /// gravity does not act on them). Validates both structs first
  /// (ValidateOrThrow: ConfigFieldError, a std::invalid_argument).
  CockpitControlsBody(PhysicsWorld& world, const CockpitConfig& cockpit,
                      const ControlsBodyConfig& bodies = {});
  ~CockpitControlsBody();
  CockpitControlsBody(const CockpitControlsBody&) = delete;
  CockpitControlsBody& operator=(const CockpitControlsBody&) = delete;

  /// Angle, position and which controls the world's proxy hands touch (from
  /// the dispatcher's contact manifolds of the latest step). A control whose
  /// pose or velocity is not finite is first put back at zero, at rest.
  ControlsState Read();
  /// Sets the torque, springs and lock; they act on every following step.
  void Apply(const ControlsActuation& actuation);

  /// Controls put back after a NaN/Inf.
  int resets() const;
  /// N: the guidance's push back along its normal at the latest step (< 0
  /// while its damping brakes a control leaving the danger; |·| <= its bound).
  double guidance_force() const;
  btRigidBody& wheel_body();
  btRigidBody& throttle_body();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Carries the controls' state and actuation between the physics thread and
/// another thread (the interface's), without either waiting: registered as a
/// step hook, it applies the latest actuation before every step and publishes
/// the state after it.
class ControlsLink final : public StepHook {
 public:
  /// Registers itself with `world`; `controls` and the link must outlive the
  /// world's thread.
  ControlsLink(PhysicsWorld& world, CockpitControlsBody& controls);

  /// Any thread: the actuation for the following steps.
  void SetActuation(const ControlsActuation& actuation) { actuation_.Store(actuation); }
  /// Any thread: the state after the latest step (all zero before the first).
  ControlsState State() const { return state_.Load(); }

  void BeforeStep() override;
  void AfterStep() override;

 private:
  CockpitControlsBody& controls_;
  Seqlock<ControlsActuation> actuation_;
  Seqlock<ControlsState> state_;
};

}  // namespace haptel::physics
