#pragma once
/// @file Time-domain passivity observer and controller (Hannaford & Ryu,
/// "Time-domain passivity control of haptic interfaces", IEEE TRO 18(1), 2002)
/// for one port the servo loop renders, per degree of freedom (x, y, z).
///
/// Sign convention. `f` is the force the hand exerts on the virtual side, the
/// reaction to the force rendered on the device (f = −rendered), and `v` the
/// device's velocity, so f·v is the power flowing INTO the virtual side. The
/// observed energy E(n) = E(n−1) + T·f·v is what the virtual side has absorbed
/// so far: E ≥ 0 while it is passive, E < 0 means it has generated energy.
/// Pressing into a spring wall (rendered force out, motion in) raises E; the
/// wall pushing the hand back out returns it; a damper raises it for good.
///
/// Observer. The device holds a command for a whole period (zero-order hold),
/// so the force commanded at tick n−1 acts over the displacement from n−1 to
/// n: the loop observes T·f·v as f(n−1)·Δx(n), causally and exactly for the
/// held force. Paired with the force of the same tick instead, a sampled
/// spring would look dissipative and the controller would never see the
/// energy the hold leaks (the leak behind Colgate's bound K < 2b/T).
///
/// Controller. When E(n) < 0 it adds the damping α = −E/(T·v²) to the port,
/// a force −α·v on the device, which over the next period dissipates T·α·v²
/// = −E: exactly the deficit, added back to E at once (H&R's form). α is
/// capped at the device's maximum damping and v² floored (min_speed²) so α
/// cannot blow up near rest; capped or floored, it dissipates less than the
/// deficit and E stays negative until the motion lets it close. A port that
/// dissipates (E ≥ 0) is left alone.
///
/// Allocation-free, lock-free, no logging: one of these per port per arm lives
/// in the servo loop. Energies are in J, damping in N·s/m, speeds in m/s.
#include <array>
#include <cstdint>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// The controller's limits (servo.passivity_* in the device file).
struct PassivityLimits {
  double max_damping = 20.0;  ///< N·s/m: the most damping the device renders stably
  double min_speed = 0.002;   ///< m/s: v² is floored at min_speed² in α = −E/(T·v²)
};

/// What a port's controller did on one tick.
struct PassivityAction {
  Vec3d damping_force{};    ///< N, to add to the port's rendered force: −α·v per axis
  Vec3d alpha{};            ///< N·s/m per axis (0 where E ≥ 0)
  double dissipated = 0.0;  ///< J, T·α·v² summed over the axes
  bool acted = false;       ///< α > 0 on some axis
};

class PassivityController {
 public:
  explicit PassivityController(const PassivityLimits& limits = PassivityLimits{})
      : limits_(limits) {}

  /// One tick of period `period_s`. `rendered` is the force the port asks of
  /// the device now (N, on the hand, before this controller), `displacement`
  /// the device's motion since the previous tick (m) and `velocity` its
  /// velocity now (m/s, what the damping acts on). Observes the energy the
  /// previous tick's force exchanged over `displacement`, then acts.
  PassivityAction Update(const Vec3d& rendered, const Vec3d& displacement, const Vec3d& velocity,
                         double period_s);

  /// Forgets the energy and the held force: after the device was lost, or
  /// when the loop has no previous position to take a displacement from.
  void Reset();

  /// Observed energy per axis, J (E < 0: the virtual side generated energy).
  const Vec3d& energy() const { return energy_; }
  const PassivityLimits& limits() const { return limits_; }

 private:
  PassivityLimits limits_;
  Vec3d energy_{};
  Vec3d held_force_{};  ///< −rendered of the previous tick: the force on the virtual side
};

}  // namespace haptel::haptics
