#pragma once
/// @file The interfaces a run may switch between (F1–F6, in the order the run
/// configuration lists them), and the switch itself: the forces ramp down
/// over `ramp_s`, the interface changes (its fields cleared), and the forces
/// ramp up again, so the hands feel no jolt; the vehicle gets a zero command
/// meanwhile. Each switch is kept with its time.
#include <memory>
#include <string>
#include <vector>

#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/mediator/run_record.hpp"  // SwitchRecord: switches are recorded as they are kept

namespace haptel::mediator {

class InterfaceSet {
 public:
  /// `interfaces` in F-key order (null entries: listed but not available in
  /// this run); `current` indexes a non-null one.
  InterfaceSet(std::vector<std::unique_ptr<interfaces::MediatorInterface>> interfaces, int current,
               double ramp_s = 0.3);

  interfaces::MediatorInterface& current() { return *interfaces_[static_cast<size_t>(current_)]; }
  const interfaces::MediatorInterface& current() const {
    return *interfaces_[static_cast<size_t>(current_)];
  }
  int current_index() const { return current_; }
  int size() const { return static_cast<int>(interfaces_.size()); }
  /// The interface at `index`, or null.
  interfaces::MediatorInterface* at(int index);

  /// Puts a built interface into the empty place `index` (one whose parts —
  /// a physics world — were built when it was first asked for).
  /// std::invalid_argument when the place is taken or out of range.
  void Provide(int index, std::unique_ptr<interfaces::MediatorInterface> interface);
  /// Asks for the interface at `index` from t_s on. False (and nothing
  /// happens) when it is the current one, missing, or a switch is under way.
  bool Request(int index, double t_s);
  /// Runs the current interface at t_s and drives a switch under way
  /// through `hal`'s force scale. Returns the motor command (zero while switching).
  TreadCommand Update(double t_s, const interfaces::VehicleFeedback& feedback, haptics::Hal& hal);
  bool switching() const { return target_ >= 0 || ramp_up_until_s_ > 0; }
  const std::vector<SwitchRecord>& switches() const { return switches_; }

 private:
  std::vector<std::unique_ptr<interfaces::MediatorInterface>> interfaces_;
  int current_ = 0;
  double ramp_s_;
  int target_ = -1;  ///< switching to this (ramping down)
  double ramp_start_s_ = 0.0;
  double ramp_up_until_s_ = -1;  ///< ramping up until then (after the swap)
  std::vector<SwitchRecord> switches_;
};

}  // namespace haptel::mediator
