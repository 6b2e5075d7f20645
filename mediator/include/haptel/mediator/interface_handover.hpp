#pragma once
/// @file The person's interface handed from one fleet vehicle to another
/// (`haptel run --fleet FILE --operator person`).
///
/// Each vehicle of a fleet has the interface that fits its kind (a robot's
/// keys, gesture or cockpit; a blimp's keys or gesture cockpit), and they
/// all render into the one haptic device. Only one of them is live at a
/// time: two cockpits would push two couplings into the same arms (and two
/// physics threads would write the HAL's one set-point slot). A turn to
/// another vehicle therefore swaps the interfaces as F1–F6 swaps them in a
/// single run (InterfaceSet): the forces ramp down through the HAL's force
/// scale over `ramp_s` (the run's switch_ramp_s) while the interface left
/// still renders them, at zero the interface left is paused (its fields
/// cleared, its physics world stopped) and the new one resumed (its physics
/// started, the person's input so far marked as seen), and the forces ramp
/// up again. No force ever steps: each tick moves the scale by at most
/// tick / ramp_s. While the old interface fades no vehicle takes the
/// person's input: the new vehicle is held safe until its interface is live.
///
/// Runs on the session thread: pausing and resuming (a physics thread
/// stopped and started) never touch the servo loop, which sees only the
/// HAL's fields, set-points and force scale through their seqlocks.
#include <vector>

#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/input.hpp"

namespace haptel::mediator {

/// What a fleet vehicle's part offers the handover: its interface's forces
/// without its command, and its force rendering paused and resumed.
class HandoverSide {
 public:
  virtual ~HandoverSide() = default;
  /// The live interface renders its forces at t_s (fields refreshed, the
  /// controls actuated); its command goes nowhere and the vehicle is not
  /// driven by it. Called while its forces fade out.
  virtual void RenderForces(double t_s, haptics::Hal& hal) = 0;
  /// Its interface stops rendering (called at zero force scale): its
  /// physics world, if any, stops coupling the hands and leaves the HAL.
  virtual void PauseForces(haptics::Hal& hal) = 0;
  /// Its interface is live again: its physics world, if any, couples the
  /// hands again; the person's input up to `now` was another vehicle's.
  virtual void ResumeForces(haptics::Hal& hal, const interfaces::InputState& now) = 0;
};

class InterfaceHandover {
 public:
  /// `sides` in the fleet's order (not owned; they outlive this). With
  /// `ramp_s` 0 the interfaces swap at once, without a fade (the automatic
  /// operator: no person holds the arms).
  InterfaceHandover(std::vector<HandoverSide*> sides, double ramp_s);

  /// Every side paused before the first turn (their physics worlds started
  /// with the session): none is live until a vehicle is turned to.
  void PauseAll(haptics::Hal& hal);

  /// Turns the person's interface to vehicle `to` (-1: none) from t_s. The
  /// first turn makes it live at once (no force was rendered before); later
  /// ones start the fade from the force scale `hal` has now. A turn during
  /// the fade down retargets it.
  void TurnTo(int to, double t_s, const haptics::Hal& hal);

  /// Each session tick, before any vehicle is driven: the fade's step (the
  /// force scale set, the interface left rendering, the swap at zero).
  /// Returns the vehicle whose interface takes the person's input and
  /// commands its vehicle this tick; -1 while the interface left fades out.
  int Tick(double t_s, haptics::Hal& hal, const interfaces::InputState& input_now);

  /// Each session tick, after the live vehicle was driven (or not): in the
  /// ramp up, the force scale. `own_switch_ramping`: the live vehicle's own
  /// interfaces are switching (F1–F6) and set the scale themselves; the
  /// lower of the two is kept then, so neither ramp steps the other.
  void Settle(double t_s, haptics::Hal& hal, bool own_switch_ramping);

  /// The vehicle whose interface is live (renders), -1 before the first turn.
  int live() const { return live_; }
  /// The vehicle the person turned to (live once the fade is down).
  int target() const { return target_; }
  bool fading_out() const { return phase_ == Phase::kDown; }
  bool swapping() const { return phase_ != Phase::kIdle; }
  /// Swaps done (an interface paused and another resumed).
  int swaps() const { return swaps_; }

 private:
  enum class Phase { kIdle, kDown, kUp };
  void Swap(haptics::Hal& hal, const interfaces::InputState& input_now);

  std::vector<HandoverSide*> sides_;
  double ramp_s_;
  Phase phase_ = Phase::kIdle;
  int live_ = -1;
  int target_ = -1;
  bool first_turn_ = true;
  double ramp_start_s_ = 0.0;
  double scale_at_start_ = 1.0;  ///< the force scale the fade down started from
  int swaps_ = 0;
};

}  // namespace haptel::mediator
