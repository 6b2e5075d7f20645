#include "haptel/haptics/twoport.hpp"

#include <algorithm>

namespace haptel::haptics {

void TwoPortPassivity::Observe(const Vec3d& displacement) {
  const double sign = end_ == ChannelEnd::kDevice ? -1.0 : 1.0;
  for (int i = 0; i < 3; ++i) {
    // The channel's own force splits into what entered and what left here;
    // the controller's damping is the hand's loss, counted apart, so that it
    // never reaches the other end as credit.
    const double work_in = sign * held_rendered_[i] * displacement[i];
    if (work_in >= 0.0) {
      energy_in_[i] += work_in;
    } else {
      energy_out_[i] -= work_in;
    }
    dissipated_[i] -= held_damping_[i] * displacement[i];
  }
}

TwoPortAction TwoPortPassivity::Control(const Vec3d& rendered, const Vec3d& remote_energy_in,
                                        const Vec3d& velocity, double period_s) {
  TwoPortAction action;
  const double floor_v2 = limits_.min_speed * limits_.min_speed;
  Vec3d damping{};
  for (int i = 0; i < 3; ++i) {
    double margin = remote_energy_in[i] - energy_out_[i] + dissipated_[i] - forgotten_[i];
    if (margin > limits_.max_credit_j) {
      forgotten_[i] += margin - limits_.max_credit_j;
      margin = limits_.max_credit_j;
    }
    if (margin >= 0.0 || period_s <= 0.0) continue;
    const double v = velocity[i];
    const double alpha = std::min(-margin / (period_s * std::max(v * v, floor_v2)), limits_.max_damping);
    action.alpha[i] = alpha;
    damping[i] = -alpha * v;
    action.acted = true;
  }
  action.damping_force = damping;
  Hold(rendered, damping);
  return action;
}

void TwoPortPassivity::Hold(const Vec3d& rendered, const Vec3d& damping) {
  held_rendered_ = rendered;
  held_damping_ = damping;
}

Vec3d TwoPortPassivity::Margin(const Vec3d& remote_energy_in) const {
  Vec3d w{};
  for (int i = 0; i < 3; ++i) {
    w[i] = std::min(remote_energy_in[i] - energy_out_[i] + dissipated_[i] - forgotten_[i], limits_.max_credit_j);
  }
  return w;
}

Vec3d TwoPortPassivity::EnergyToSend(const Vec3d& remote_energy_in) const {
  const Vec3d margin = Margin(remote_energy_in);
  Vec3d send{};
  for (int i = 0; i < 3; ++i) send[i] = energy_in_[i] + std::min(0.0, margin[i]);
  return send;
}

void TwoPortPassivity::Reset() {
  energy_in_ = energy_out_ = dissipated_ = forgotten_ = held_rendered_ = held_damping_ = Vec3d{};
}

}  // namespace haptel::haptics
