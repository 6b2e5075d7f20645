#include "haptel/mediator/operator.hpp"

#include "haptel/haptics/sim_device.hpp"

namespace haptel::mediator {

void HoldHand(haptics::SimDevice& device, haptics::Side side, const interfaces::HandGoal& goal) {
  device.SetOperatorTarget(side, goal.position);
  device.SetWristOrientation(side, goal.orientation);
  device.SetGlovePosture(side, goal.glove);
}

void HoldHands(haptics::SimDevice& device, const interfaces::HandTargets& targets) {
  for (int i = 0; i < haptics::kSides; ++i) {
    if (targets[i]) HoldHand(device, static_cast<haptics::Side>(i), *targets[i]);
  }
}

void PlaceHands(haptics::SimDevice& device, const interfaces::HandTargets& targets) {
  for (int i = 0; i < haptics::kSides; ++i) {
    if (targets[i]) device.Place(static_cast<haptics::Side>(i), targets[i]->position);
  }
  HoldHands(device, targets);
}

AutomaticOperator::AutomaticOperator(const Track& track, const OperatorConfig& config,
                                     const TreadDriveConfig& drive, haptics::SimDevice& device,
                                     const DriverProfile& profile, int experience)
    : driver_(track, config, drive, profile, experience), device_(device) {}

void AutomaticOperator::Prepare(const interfaces::MediatorInterface& interface) {
  const interfaces::HandTargets neutral = interface.HandTargetsFor({});
  for (int i = 0; i < haptics::kSides; ++i) {
    if (!neutral[i]) continue;
    interfaces::HandGoal start = *neutral[i];
    for (int k = 0; k < 3; ++k) start.position[k] += start.approach[k];
    start.glove = {};
    const auto side = static_cast<haptics::Side>(i);
    device_.Place(side, start.position);
    HoldHand(device_, side, start);
  }
}

void AutomaticOperator::Act(double t_s, const interfaces::MediatorInterface& interface) {
  HoldHands(device_, driver_.Act(t_s, interface));
}

void AutomaticOperator::Rest(const interfaces::MediatorInterface& interface) {
  HoldHands(device_, interface.HandTargetsFor({}));
}

}  // namespace haptel::mediator
