#pragma once
/// @file A mediator interface: turns the operator's hands into vehicle
/// commands and tells the operator, through forces, what the vehicle meets.
#include <array>
#include <limits>
#include <optional>
#include <string>

#include "haptel/core/range_scan.hpp"
#include "haptel/core/tread_command.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/input.hpp"

namespace haptel::interfaces {

/// The motion a driver wants, before it is mixed into each tread's command
/// (Mix: left = forward − turn, right = forward + turn; turn > 0 turns
/// left). Both in [-1, 1].
struct MotionIntent {
  double forward = 0.0;
  double turn = 0.0;
};

/// Differential mix: left = forward − turn, right = forward + turn, scaled
/// down together (keeping their ratio) when either leaves [-1, 1].
TreadCommand Mix(double forward, double turn);

/// What the vehicle reports that an interface reacts to.
struct VehicleFeedback {
  /// The bumpers and speed alone (a vehicle without range sensors), as most
  /// callers give them; the scan, where there is one, after.
  VehicleFeedback(bool bumper_left_ = false, bool bumper_right_ = false, double speed_ = 0.0,
                  const RangeScan& ranges_ = {})
      : bumper_left(bumper_left_), bumper_right(bumper_right_), speed(speed_), ranges(ranges_) {}
  bool bumper_left = false;
  bool bumper_right = false;
  double speed = 0.0;  ///< m/s
  /// What the vehicle's range sensors see now (count 0: it has none).
  RangeScan ranges;
};

/// What haptic shared control's guidance does now (shared_control.hpp): for
/// the view, the recorder and tests. In the space of what the operator moves:
/// gesture-shared's is the right hand's position (m, device frame);
/// cockpit-shared's the controls' (x: the lever's travel, y: the rim's arc,
/// wheel angle × radius, + left; m).
struct Guidance {
  double time_to_collision_s = std::numeric_limits<double>::infinity();
  double danger = 0.0;             ///< 0 (beyond the horizon) .. 1 (collision now)
  bool active = false;             ///< a guidance plane is set
  haptics::Vec3d point{};          ///< on the boundary of the safe commands, m
  haptics::Vec3d normal{1, 0, 0};  ///< unit, towards the dangerous commands
  haptics::Vec3d
      force{};  ///< N: what the plane pushes (forward, left) where the hand or controls are now
  double max_force = 0.0;  ///< N: the most it may push (the config's bound)
};

/// How a driver holds one hand to express an intent.
struct HandGoal {
  haptics::Vec3d position{};                          ///< wrist, m, device frame
  std::array<double, 4> orientation{1, 0, 0, 0};      ///< wrist quaternion (w, x, y, z)
  std::array<double, haptics::kGloveJoints> glove{};  ///< joint angles, rad (all 0: open hand)
  /// Where the hand comes in from, open, before it closes on a control: an
  /// offset (m) from `position`. Zero when there is nothing to grasp.
  haptics::Vec3d approach{};
};

/// Where a driver's hands go to express an intent (per side; empty = that
/// hand is not used by the interface).
using HandTargets = std::array<std::optional<HandGoal>, haptics::kSides>;

/// What a person's head-up display shows of an interface: a speedometer and
/// turn indicators (the HUD cockpits', kept on the gesture interface as in
/// the thesis). The view draws it as the interface fills it.
struct HudReading {
  bool shown = false;      ///< drawn at all
  double speed_mps = 0.0;  ///< the speedometer
  bool turn_left = false;  ///< indicator lights
  bool turn_right = false;
  bool throttle_locked = false;
};

/// What every interface is, whatever family of vehicle it drives (`Family`:
/// RobotFamily, BlimpFamily below): its command, the intent a driver holds
/// their hands for, and what it reads each tick besides the HAL. The session,
/// the catalogue (catalog.hpp) and the view are written once over it; none
/// asks an interface its name.
template <class Family>
class Interface {
 public:
  using Command = typename Family::Command;
  using Intent = typename Family::Intent;
  using Reading = typename Family::Reading;

  virtual ~Interface() = default;
  virtual std::string name() const = 0;

  /// Session thread, at the session rate: reads the hands from the HAL (or
  /// the person's input in `reading`), sets the force fields in the HAL and
  /// returns the command.
  virtual Command Update(double t_s, const Reading& reading, haptics::Hal& hal) = 0;

  /// Where a person would put their hands to express `intent` — used by the
  /// automatic operator, and by tests (none for keys and controllers).
  virtual HandTargets HandTargetsFor(const Intent& intent) const = 0;

  /// The interface is taken up again (a fleet's operator turned back to its
  /// vehicle): the person's input up to `now` was given to other vehicles,
  /// so an interface that counts key presses marks them as seen and starts
  /// from rest, not from the levels it was left at. Session thread.
  virtual void Rebase(const InputState& /*now*/) {}

  /// The person's input went away for good (a game controller disconnected).
  virtual bool lost() const { return false; }

  /// The line of help the view shows in a person's first seconds (null:
  /// none); `switchable`: the person may switch interfaces (F1–F6).
  virtual const char* Help(bool /*switchable*/) const { return nullptr; }

  /// What stops the person driving now and what to do about it (a game
  /// controller not connected); null: nothing. The view shows it for as long
  /// as it lasts, in place of the help, and the session logs it. A string
  /// that lives as long as the interface. Session thread.
  virtual const char* Notice() const { return nullptr; }
};

/// The robot: each tread's command, from the hands and what the robot reports.
struct RobotFamily {
  using Command = TreadCommand;
  using Intent = MotionIntent;
  using Reading = VehicleFeedback;
};

class MediatorInterface : public Interface<RobotFamily> {
 public:
  /// Whether the interface has physical controls that need a physics world.
  virtual bool NeedsPhysics() const = 0;

  /// What a driver perceives of the interface, for the simulated driver:
  /// whether it shows the vehicle's speed (a speedometer)...
  virtual bool ShowsSpeed() const { return false; }
  /// ...and whether its controls stay where the hand leaves them (false:
  /// there are none, or they spring back to zero when released).
  virtual bool ControlsStayPut() const { return false; }

  /// Haptic shared control's guidance as of the last Update, for the view to
  /// draw what pushes the hand; nullopt for interfaces without it.
  virtual std::optional<Guidance> CurrentGuidance() const { return std::nullopt; }

  /// Between the session's ticks: the command the hands or controls give
  /// now, read without stepping anything (no field set, no control
  /// actuated, no filter advanced), so that a change reaches the vehicle
  /// within a millisecond rather than at the next tick (issue 36: input to
  /// command). The same command Update would return for the same hands or
  /// controls; nullopt: only Update gives it (keys, controllers). Session thread.
  virtual std::optional<TreadCommand> CommandNow(double /*t_s*/,
                                                 const haptics::Hal& /*hal*/) const {
    return std::nullopt;
  }

  /// A line about its controls for the run's progress log, given the command
  /// they gave ("": nothing beyond the command).
  virtual std::string ProgressLine(const TreadCommand& /*motors*/) const { return {}; }

  /// What its head-up display shows as of the last Update, given what the
  /// robot reported and the command it was given; nullopt: it has none.
  virtual std::optional<HudReading> Hud(const VehicleFeedback& /*feedback*/,
                                        const TreadCommand& /*motors*/) const {
    return std::nullopt;
  }
};

}  // namespace haptel::interfaces
