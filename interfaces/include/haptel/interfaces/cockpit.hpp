#pragma once
/// @file The cockpit interfaces (`cockpit`, `cockpit-hud`, `cockpit-assisted`):
/// a steering wheel and a throttle lever that live as bodies in the physics
/// world, touched and grasped by the proxy hands.
///
/// The interface never touches physics itself: it reads the controls and
/// actuates them through a ControlsPort (the session connects the port to
/// the physics world's controls; tests use a plain one). The forces the
/// operator feels come from the proxy hands' coupling, not from a field.
///
/// Hands: the left hand holds the wheel at the top of its rim and turns with
/// it; the right hand holds the throttle lever's bar. Both grasp from above,
/// palm down, fingers forward over the rim or bar and closed around it.
///
/// cockpit-shared (a `shared_control` section) adds haptic shared control
/// (shared_control.hpp) on the controls themselves: the prediction and the
/// guidance plane are gesture-shared's, in the controls' space (the lever's
/// travel, m, as "forward"; the rim's arc, wheel angle × radius, m, as
/// "left"), and the physics world renders the plane's spring on the lever
/// and the wheel at its own rate (ControlActuation's guidance). The hands
/// holding them feel it through the proxy hands' coupling, bounded at
/// max_force, and can push through: the command stays the controls' own.
#include <optional>

#include "haptel/interfaces/cockpit_logic.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/interfaces/shared_control.hpp"

namespace haptel::interfaces {

/// Where the cockpit's controls live: read their state, set what they feel.
/// Both calls are made from the interface's (session) thread.
class ControlsPort {
 public:
  virtual ~ControlsPort() = default;
  virtual CockpitControls Controls() const = 0;
  virtual void Actuate(const ControlActuation& actuation) = 0;
};

/// How the operator's hand sits on a bar-like grip (the wheel's rim, the
/// lever's bar), from the proxy hand's shipped dimensions (config/physics.yaml)
/// and the controls' bodies (physics/cockpit_controls.hpp).
struct GripGeometry {
  /// Wrist behind the bar's axis, along the fingers: palm (9 cm) plus half a
  /// metacarpal, so the bar lies under the metacarpals and closing the
  /// fingers wraps the other phalanges around it.
  double reach = 0.115;
  /// Wrist above the bar's axis: bar radius (1.2 cm) + phalanx radius (0.8 cm)
  /// + 3 mm, so the closed fingers pull the bar up against the metacarpals.
  double height = 0.023;
  /// The open hand comes down from this far above its grip.
  double approach = 0.05;
  /// Closed hand: flexion of the four fingers' joints (MCP, PIP, DIP), rad.
  std::array<double, 3> flexion{0.2, 1.6, 1.4};
  /// A held control that has slipped in the hand is seen and made up for, as
  /// a person looking at it would: over this time constant, s.
  double slip_time_constant = 0.3;
  /// The most slip made up for: lever m, wheel rad (beyond: not a slip).
  double max_lever_slip = 0.03;
  double max_wheel_slip = 0.3;
};

class CockpitInterface final : public MediatorInterface {
 public:
  /// Keeps a reference to `port`, which must outlive the interface. Validates
  /// `config` first (CockpitConfig::ValidateOrThrow: ConfigFieldError).
  /// `vehicle`: what shared control predicts the vehicle's motion with
  /// (unused without it).
  CockpitInterface(const CockpitConfig& config, ControlsPort& port, const GripGeometry& grip = {},
                   const VehicleGeometry& vehicle = {});

  std::string name() const override { return logic_.config().name; }
  /// Controls → motors; bumper → shake and lock; assisted → return springs.
  TreadCommand Update(double t_s, const VehicleFeedback& feedback, haptics::Hal& hal) override;
  /// Left hand on the wheel turned to the intent's angle, right hand on the
  /// lever at the intent's position, both closed — each shifted by how far
  /// that control has slipped in the hand holding it (seen in Update).
  HandTargets HandTargetsFor(const MotionIntent& intent) const override;
  /// The controls as the physics world holds them now, mapped (the lock on
  /// the lever after a contact included).
  std::optional<TreadCommand> CommandNow(double t_s, const haptics::Hal& hal) const override;
  bool NeedsPhysics() const override { return true; }
  bool ShowsSpeed() const override { return logic_.config().hud; }
  bool ControlsStayPut() const override { return !logic_.config().return_to_zero; }

  /// The view elements after the latest Update (all off without a HUD).
  const HudState& hud() const { return hud_; }
  /// The wheel, the throttle, the motors and the HUD.
  std::string ProgressLine(const TreadCommand& motors) const override;
  /// The HUD cockpits show what their logic computed, exactly.
  std::optional<HudReading> Hud(const VehicleFeedback& /*feedback*/,
                                const TreadCommand& /*motors*/) const override {
    return HudReading{logic_.config().hud, hud_.speed, hud_.turn_left, hud_.turn_right,
                      hud_.throttle_locked};
  }
  /// The controls as read by the latest Update.
  const CockpitControls& controls() const { return controls_; }
  const CockpitLogic& logic() const { return logic_; }
  /// How far the held lever (m) and wheel (rad) sit behind the hands that
  /// hold them, filtered; 0 while not held.
  double lever_slip() const { return lever_slip_; }
  double wheel_slip() const { return wheel_slip_; }
  /// Shared control's guidance as of the last Update, in the controls' space
  /// (point and normal: lever m, rim arc m; force: N on the lever forward and
  /// along the rim towards the left); inactive without shared control.
  const Guidance& guidance() const { return guidance_; }
  bool shared() const { return shared_.has_value(); }
  std::optional<Guidance> CurrentGuidance() const override {
    return shared_ ? std::optional<Guidance>(guidance_) : std::nullopt;
  }
  /// What the latest Update asked the controls to feel.
  const ControlActuation& actuation() const { return actuation_; }

 private:
  CockpitLogic logic_;
  ControlsPort& port_;
  GripGeometry grip_;
  CockpitControls controls_;
  HudState hud_;
  double lever_slip_ = 0.0;
  double wheel_slip_ = 0.0;
  double last_update_s_ = -1.0;
  std::optional<SharedControl> shared_;
  PersistentEchoes echoes_;
  Guidance guidance_;
  ControlActuation actuation_;
};

}  // namespace haptel::interfaces
