#pragma once
/// @file The gesture interface: no controls and no left hand.
///
/// The right hand's offset from a neutral point maps to forward speed (x) and
/// turning (y), past a dead zone. A force field pulls the hand back to
/// neutral, stronger with distance, so effort tells the driver how fast they
/// go. When a bumper switch closes, a haptic wall resists further hand motion
/// in the direction that drove the robot into the obstacle; it releases once
/// the contact has been clear for `wall_release_s`.
///
/// gesture-shared (a `shared_control` section) adds haptic shared control
/// (shared_control.hpp): a bounded push away from commands that would lead
/// into an obstacle the vehicle's range sensors see within the horizon.
#include <optional>

#include "haptel/config/gesture.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/interfaces/shared_control.hpp"

namespace haptel::interfaces {

class GestureInterface final : public MediatorInterface {
 public:
  /// Validates `config` first (GestureConfig::ValidateOrThrow: ConfigFieldError).
  /// `vehicle`: what shared control predicts the vehicle's motion with (unused
  /// without it).
  explicit GestureInterface(const GestureConfig& config, const VehicleGeometry& vehicle = {});

  std::string name() const override { return config_.name; }
  TreadCommand Update(double t_s, const VehicleFeedback& feedback, haptics::Hal& hal) override;
  HandTargets HandTargetsFor(const MotionIntent& intent) const override;
  /// Map of the right hand's latest sample (zero without one, as Update).
  std::optional<TreadCommand> CommandNow(double t_s, const haptics::Hal& hal) const override;
  bool NeedsPhysics() const override { return false; }
  /// The thesis kept the speedometer and the indicators on the gesture interface.
  bool ShowsSpeed() const override { return true; }
  /// The speedometer, and an indicator lit by a motor difference past kTurnShown.
  std::optional<HudReading> Hud(const VehicleFeedback& feedback,
                                const TreadCommand& motors) const override {
    return HudReading{true, feedback.speed, motors.right - motors.left > kTurnShown,
                      motors.left - motors.right > kTurnShown, false};
  }
  static constexpr double kTurnShown = 0.1;  ///< motor difference that lights an indicator

  /// Pure mapping from a right-hand position to motor commands.
  TreadCommand Map(const haptics::Vec3d& right_hand) const;
  /// The force field for the current state (what Update puts in the HAL).
  const haptics::ForceField& field() const { return field_; }
  bool wall_active() const { return field_.wall_active; }
  /// Shared control's guidance as of the last Update (inactive without it).
  const Guidance& guidance() const { return guidance_; }
  bool shared() const { return shared_.has_value(); }
  std::optional<Guidance> CurrentGuidance() const override {
    return shared_ ? std::optional<Guidance>(guidance_) : std::nullopt;
  }

 private:
  GestureConfig config_;
  haptics::ForceField field_;
  double last_contact_s_ = -1e9;
  std::optional<SharedControl> shared_;
  PersistentEchoes echoes_;
  Guidance guidance_;
};

}  // namespace haptel::interfaces
