#include "haptel/haptics/twoport.hpp"

#include <algorithm>
#include <cmath>

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
    const double alpha =
        std::min(-margin / (period_s * std::max(v * v, floor_v2)), limits_.max_damping);
    action.alpha[i] = alpha;
    damping[i] = -alpha * v;
    action.acted = true;
  }
  action.damping_force = damping;
  Hold(rendered, damping);
  return action;
}

const Vec3d& TwoPortPassivity::ControlPosition(const Vec3d& remote_energy_in, double period_s,
                                               bool* acted) {
  const double floor_f = limits_.max_damping * limits_.min_speed;
  const Vec3d margin = Margin(remote_energy_in);
  for (int i = 0; i < 3; ++i) {
    const double f = held_rendered_[i];
    if (period_s <= 0.0) continue;
    if (margin[i] < 0.0) {
      double left = margin[i];
      if (std::abs(f) >= floor_f) {
        const double cap = std::min(period_s * std::abs(f) / limits_.max_damping,
                                    std::max(0.0, limits_.max_offset_m - std::abs(offset_[i])));
        // f·step = −W: moved against the environment's force, it returns the deficit.
        const double step = std::clamp(-margin[i] / f, -cap, cap);
        if (step != 0.0) {
          offset_[i] += step;
          dissipated_[i] += f * step;
          left += f * step;
          if (acted != nullptr) *acted = true;
        }
      }
      charged_[i] = std::max(charged_[i], -left);
    } else if (offset_[i] != 0.0) {
      // Drift back, paid from the margin: a step along −f costs f·r of it.
      double r =
          std::clamp(-offset_[i], -limits_.min_speed * period_s, limits_.min_speed * period_s);
      const double cost = -f * r;
      if (cost > margin[i]) r *= margin[i] / cost;
      offset_[i] += r;
      if (f * r < 0.0) {
        energy_out_[i] -= f * r;
      } else {
        dissipated_[i] += f * r;  // the environment lets go of it: lost, not credit
      }
    }
  }
  return offset_;
}

void TwoPortPassivity::ChargeDeficit(const Vec3d& remote_energy_in) {
  const Vec3d margin = Margin(remote_energy_in);
  for (int i = 0; i < 3; ++i) charged_[i] = std::max(charged_[i], -margin[i]);
}

void TwoPortPassivity::Hold(const Vec3d& rendered, const Vec3d& damping) {
  held_rendered_ = rendered;
  held_damping_ = damping;
}

Vec3d TwoPortPassivity::Margin(const Vec3d& remote_energy_in) const {
  Vec3d w{};
  for (int i = 0; i < 3; ++i) {
    w[i] = std::min(remote_energy_in[i] - energy_out_[i] + dissipated_[i] - forgotten_[i],
                    limits_.max_credit_j);
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
  offset_ = charged_ = Vec3d{};
}

}  // namespace haptel::haptics
