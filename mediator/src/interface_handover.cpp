#include "haptel/mediator/interface_handover.hpp"

#include <algorithm>

namespace haptel::mediator {

InterfaceHandover::InterfaceHandover(std::vector<HandoverSide*> sides, double ramp_s)
    : sides_(std::move(sides)), ramp_s_(std::max(ramp_s, 0.0)) {}

void InterfaceHandover::PauseAll(haptics::Hal& hal) {
  for (HandoverSide* side : sides_) side->PauseForces(hal);
}

void InterfaceHandover::TurnTo(int to, double t_s, const haptics::Hal& hal) {
  if (phase_ == Phase::kDown) {
    target_ = to;  // still fading the one left: the swap at zero goes to the newest choice
    return;
  }
  if (to == live_ && phase_ == Phase::kIdle) return;
  target_ = to;
  phase_ = Phase::kDown;
  ramp_start_s_ = t_s;
  // From where the forces are now (full, or part way up a ramp): no step.
  scale_at_start_ = hal.force_scale();
}

void InterfaceHandover::Swap(haptics::Hal& hal, const interfaces::InputState& input_now) {
  if (target_ == live_) return;  // turned back before the swap: the same interface ramps up again
  if (live_ >= 0) {
    // With a fade, the fields of the interface left go with it (at zero
    // scale: nothing felt changes). Without one (the automatic operator),
    // the fields stay until the new interface writes its own, as before.
    if (ramp_s_ > 0.0) hal.ZeroForces();
    sides_[static_cast<size_t>(live_)]->PauseForces(hal);
  }
  if (target_ >= 0) sides_[static_cast<size_t>(target_)]->ResumeForces(hal, input_now);
  if (live_ >= 0 && target_ >= 0) ++swaps_;
  live_ = target_;
}

int InterfaceHandover::Tick(double t_s, haptics::Hal& hal,
                            const interfaces::InputState& input_now) {
  if (phase_ != Phase::kDown) return live_;
  if (live_ < 0 || ramp_s_ <= 0.0) {
    // Nothing rendered yet (the first turn), or no fade asked for: at once.
    Swap(hal, input_now);
    phase_ = Phase::kIdle;
    return live_;
  }
  const double scale = scale_at_start_ - (t_s - ramp_start_s_) / ramp_s_;
  if (scale > 0.0) {
    // Fading: the interface left still renders its forces, scaled down;
    // nobody takes the person's input meanwhile.
    hal.SetForceScale(scale);
    sides_[static_cast<size_t>(live_)]->RenderForces(t_s, hal);
    return -1;
  }
  hal.SetForceScale(0.0);
  Swap(hal, input_now);
  if (live_ < 0) {
    phase_ = Phase::kIdle;  // none left to turn to: the forces stay at zero
    return -1;
  }
  phase_ = Phase::kUp;
  ramp_start_s_ = t_s;
  return live_;
}

void InterfaceHandover::Settle(double t_s, haptics::Hal& hal, bool own_switch_ramping) {
  if (phase_ != Phase::kUp) return;
  const double up = (t_s - ramp_start_s_) / ramp_s_;
  if (up >= 1.0) {
    phase_ = Phase::kIdle;
    // The interface's own switch, if one runs, holds the scale from now on.
    if (!own_switch_ramping) hal.SetForceScale(1.0);
    return;
  }
  hal.SetForceScale(own_switch_ramping ? std::min(up, hal.force_scale()) : up);
}

}  // namespace haptel::mediator
