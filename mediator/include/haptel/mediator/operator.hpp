#pragma once
/// @file Who drives: the session's operator part.
///
/// `auto` is the simulated driver (AutoOperator) acting on the simulated
/// device's arms; `person` is a human, who acts on the device, the keyboard
/// or a game controller directly, so the session has nothing to do for them.
/// A new kind of operator is a new Operator, not an edit of the session.
#include <memory>
#include <string>

#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/mediator/auto_operator.hpp"

namespace haptel::haptics {
class SimDevice;
}

namespace haptel::mediator {

/// A simulated person holds a hand of the simulated device as `goal` says:
/// where the wrist is, how it turns, the glove's posture.
void HoldHand(haptics::SimDevice& device, haptics::Side side, const interfaces::HandGoal& goal);
/// HoldHand for each hand `targets` has (the others as they are).
void HoldHands(haptics::SimDevice& device, const interfaces::HandTargets& targets);
/// Before the servo loop runs: puts each hand `targets` has at rest at its
/// target, held there.
void PlaceHands(haptics::SimDevice& device, const interfaces::HandTargets& targets);

class Operator {
 public:
  virtual ~Operator() = default;
  /// "auto" or "person".
  virtual std::string kind() const = 0;
  /// Before the servo loop starts: put the hands where this operator starts.
  virtual void Prepare(const interfaces::MediatorInterface& /*interface*/) {}
  /// What the operator sees of the vehicle.
  virtual void Observe(const Observation& /*observation*/) {}
  /// Session thread, at the session rate, once the vehicle answers.
  virtual void Act(double /*t_s*/, const interfaces::MediatorInterface& /*interface*/) {}
  /// The interface let go of the vehicle after the operator drove it (a
  /// hand out of reach, or not seen to be held): bring the hands back to its
  /// neutral, so that it engages again.
  virtual void Rest(const interfaces::MediatorInterface& /*interface*/) {}
  /// The hands hold the interface's controls (always, for a person: the
  /// session cannot tell).
  virtual bool grasped(double /*t_s*/) const { return true; }
  /// Whether the operator can change interfaces during a run.
  virtual bool can_switch() const { return true; }
};

/// The simulated driver moving the simulated device's arms.
class AutomaticOperator final : public Operator {
 public:
  /// Keeps references to `track` and `device`.
  AutomaticOperator(const Track& track, const OperatorConfig& config, const TreadDriveConfig& drive,
                    haptics::SimDevice& device, const DriverProfile& profile = {},
                    int experience = 0);
  std::string kind() const override { return "auto"; }
  /// Hands at the interface's neutral — or, for controls to grasp, open above them.
  void Prepare(const interfaces::MediatorInterface& interface) override;
  void Observe(const Observation& observation) override { driver_.Observe(observation); }
  void Act(double t_s, const interfaces::MediatorInterface& interface) override;
  void Rest(const interfaces::MediatorInterface& interface) override;
  bool grasped(double t_s) const override { return driver_.grasped(t_s); }
  /// It learned one interface's grasp; it does not switch.
  bool can_switch() const override { return false; }
  const AutoOperator& driver() const { return driver_; }

 private:
  AutoOperator driver_;
  haptics::SimDevice& device_;
};

/// A human at the controls.
class PersonOperator final : public Operator {
 public:
  std::string kind() const override { return "person"; }
};

}  // namespace haptel::mediator
