#include "haptel/mediator/interface_set.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace haptel::mediator {

InterfaceSet::InterfaceSet(std::vector<std::unique_ptr<interfaces::MediatorInterface>> interfaces,
                           int current, double ramp_s)
    : interfaces_(std::move(interfaces)), current_(current), ramp_s_(std::max(ramp_s, 1e-3)) {
  if (current_ < 0 || current_ >= size() || !interfaces_[static_cast<size_t>(current_)]) {
    throw std::invalid_argument("InterfaceSet: the current interface must exist");
  }
}

interfaces::MediatorInterface* InterfaceSet::at(int index) {
  return index >= 0 && index < size() ? interfaces_[static_cast<size_t>(index)].get() : nullptr;
}

void InterfaceSet::Provide(int index, std::unique_ptr<interfaces::MediatorInterface> interface) {
  if (index < 0 || index >= size() || interfaces_[static_cast<size_t>(index)] || !interface) {
    throw std::invalid_argument("InterfaceSet::Provide: place " + std::to_string(index) +
                                " is not an empty place");
  }
  interfaces_[static_cast<size_t>(index)] = std::move(interface);
}

bool InterfaceSet::Request(int index, double t_s) {
  if (switching() || index == current_ || at(index) == nullptr) return false;
  target_ = index;
  ramp_start_s_ = t_s;
  return true;
}

TreadCommand InterfaceSet::Update(double t_s, const interfaces::VehicleFeedback& feedback,
                                  haptics::Hal& hal) {
  if (target_ >= 0) {
    // Ramping down: the old interface still renders its forces, fading.
    const double down = (t_s - ramp_start_s_) / ramp_s_;
    if (down < 1.0) {
      hal.SetForceScale(1.0 - down);
      current().Update(t_s, feedback, hal);
      return {};
    }
    hal.SetForceScale(0.0);
    hal.ZeroForces();  // the old interface's fields go with it
    switches_.push_back({t_s, current().name(), interfaces_[static_cast<size_t>(target_)]->name()});
    current_ = target_;
    target_ = -1;
    ramp_start_s_ = t_s;
    ramp_up_until_s_ = t_s + ramp_s_;
  }
  TreadCommand command = current().Update(t_s, feedback, hal);
  if (ramp_up_until_s_ > 0) {
    const double up = (t_s - ramp_start_s_) / ramp_s_;
    hal.SetForceScale(std::min(1.0, up));
    if (up < 1.0) return {};
    ramp_up_until_s_ = -1;
  }
  return command;
}

}  // namespace haptel::mediator
