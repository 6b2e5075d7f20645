#include "haptel/haptics/servo_passivity.hpp"

#include <algorithm>

#include "haptel/haptics/servo_loop.hpp"

namespace haptel::haptics {

ArmPassivity::ArmPassivity(const ServoLoopConfig& servo, bool observe_link)
    : one_port_(servo.passivity),
      observe_link_(observe_link),
      admittance_(servo.passivity_link_admittance) {
  const PassivityLimits limits{servo.passivity_max_damping, servo.passivity_min_speed};
  field_port_ = PassivityController(limits);
  coupling_port_ = PassivityController(limits);
  TwoPortLimits link_limits;
  link_limits.max_damping = limits.max_damping;
  link_limits.min_speed = limits.min_speed;
  link_end_ = TwoPortPassivity(ChannelEnd::kLoop, link_limits);
}

void ArmPassivity::OnLost(Device& device, Side side) {
  field_port_.Reset();
  coupling_port_.Reset();
  link_reporting_ = false;
  if (link_end_.energy_in() != Vec3d{} || link_remote_.acted_ticks != 0) {
    link_base_ticks_ += link_remote_.acted_ticks;
    link_base_dissipated_j_ += link_remote_.dissipated_j;
    link_remote_ = LinkEnergy{};
    link_end_.Reset();
    device.RestartLinkEnergy(side);
  }
}

void ArmPassivity::ObserveLink(Device& device, Side side, const Vec3d& displacement,
                               double period_s, Vec3d& position, ServoCounters& counters) {
  link_reporting_ = observe_link_ && device.LinkPassivity(side, link_remote_);
  if (!observe_link_) return;
  link_end_.Observe(displacement);
  if (!link_reporting_) return;
  ++counters.passivity_link_ticks;
  Vec3d remote_in{};
  for (int i = 0; i < 3; ++i) remote_in[i] = link_remote_.energy_in[i] - link_remote_.charged[i];
  const double was = link_end_.dissipated_total_j();
  bool acted = false;
  if (admittance_) {
    const Vec3d& offset = link_end_.ControlPosition(remote_in, period_s, &acted);
    for (int i = 0; i < 3; ++i) position[i] += offset[i];
  } else {
    link_end_.ChargeDeficit(remote_in);
  }
  counters.passivity_dissipated_j += link_end_.dissipated_total_j() - was;
  if (acted) ++counters.passivity_ticks;
  counters.passivity_device_ticks = link_base_ticks_ + link_remote_.acted_ticks;
  counters.passivity_device_dissipated_j = link_base_dissipated_j_ + link_remote_.dissipated_j;
  counters.passivity_device_max_alpha =
      std::max(counters.passivity_device_max_alpha, link_remote_.max_alpha);
}

void ArmPassivity::DampPorts(const Vec3d& field, const Vec3d& coupling, const Vec3d& displacement,
                             const Vec3d& velocity, double period_s, Vec3d& force,
                             ServoCounters& counters) {
  if (!one_port_ || link_reporting_) return;
  bool acted = false;
  for (PassivityController* port : {&field_port_, &coupling_port_}) {
    const PassivityAction a =
        port->Update(port == &field_port_ ? field : coupling, displacement, velocity, period_s);
    if (!a.acted) continue;
    acted = true;
    counters.passivity_dissipated_j += a.dissipated;
    for (int i = 0; i < 3; ++i) {
      force[i] += a.damping_force[i];
      counters.passivity_max_alpha = std::max(counters.passivity_max_alpha, a.alpha[i]);
    }
  }
  if (acted) ++counters.passivity_ticks;
}

void ArmPassivity::ReportLink(Device& device, Side side, const Vec3d& wrist,
                              const ServoCounters& counters) {
  if (!observe_link_) return;
  link_end_.Hold(wrist);
  device.SetLinkEnergy(
      side, LinkEnergy{link_end_.energy_in(), link_end_.charged(), link_end_.dissipated_total_j(),
                       counters.passivity_ticks, 0.0});
}

}  // namespace haptel::haptics
