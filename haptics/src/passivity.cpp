#include "haptel/haptics/passivity.hpp"

#include <algorithm>

namespace haptel::haptics {

PassivityAction PassivityController::Update(const Vec3d& rendered, const Vec3d& displacement,
                                            const Vec3d& velocity, double period_s) {
  PassivityAction action;
  const double floor_v2 = limits_.min_speed * limits_.min_speed;
  for (int i = 0; i < 3; ++i) {
    // The previous tick's force acted over the displacement since (zero-order hold).
    energy_[i] += held_force_[i] * displacement[i];
    // The port's own force, not the controller's: the damping's dissipation
    // is credited below, once, as H&R add it back.
    held_force_[i] = -rendered[i];
    if (energy_[i] >= 0.0 || period_s <= 0.0) continue;
    const double v = velocity[i];
    const double alpha =
        std::min(-energy_[i] / (period_s * std::max(v * v, floor_v2)), limits_.max_damping);
    const double dissipated = period_s * alpha * v * v;
    energy_[i] += dissipated;
    action.alpha[i] = alpha;
    action.damping_force[i] = -alpha * v;
    action.dissipated += dissipated;
    action.acted = true;
  }
  return action;
}

void PassivityController::Reset() {
  energy_ = Vec3d{};
  held_force_ = Vec3d{};
}

}  // namespace haptel::haptics
