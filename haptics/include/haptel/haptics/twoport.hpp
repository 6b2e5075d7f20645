#pragma once
/// @file Time-domain passivity of a delayed channel, as a two-port (Ryu,
/// Preusche, Hannaford & Hirzinger, "Time domain passivity control with
/// reference energy following", IEEE TCST 13(5), 2005; Artigas, Ryu,
/// Preusche & Hirzinger, "Network representation and passivity of delayed
/// teleoperation systems", IROS 2011), per degree of freedom (x, y, z).
///
/// The channel. The device sends its position to the servo loop; the loop
/// sends back the force it renders; between them each way lies a delay (the
/// network, the device's server). A delay is not passive: the force that
/// reaches the arm was computed from where the arm was a round trip ago, and
/// the difference can feed an oscillation energy (the virtual wall that
/// pushes harder on the way out than it resisted on the way in). A one-port
/// observer in the loop cannot see it: it pairs the loop's force with the
/// loop's (delayed) positions, which are consistent with each other.
///
/// Two observers. Each end of the channel observes the energy that crosses
/// it and splits it, tick by tick, by the sign of the power: E_in, what
/// entered the channel at this end, and E_out, what left it here. Both only
/// grow. Each end sends its E_in to the other along with its samples (the
/// device with its positions, the loop with its forces), so each end knows
/// the other's E_in as it was a delay ago. The channel has been passive so
/// far, seen from one end, while what left it there has not exceeded what
/// entered it at the other end: E_out(n) ≤ E_in,remote(n − delay).
///
/// Sign convention. At either end `force` is the force rendered on the hand
/// (N, as the loop commands it) and `displacement` the hand's motion over
/// the period just ended (m, as seen at that end). At the device end the arm
/// feeds the channel when it moves against the force: power in = −f·v. At
/// the loop end the channel drives the virtual environment with the motion
/// and the environment answers with the force; it feeds the channel when
/// the force pushes along the motion: power in = +f·v. As in passivity.hpp
/// the force held over a period (zero-order hold) is paired with the motion
/// over that period.
///
/// The controller (impedance type, at the end whose output is a force: the
/// device's). The margin W(n) = E_in,remote(n − delay) − E_out(n) + D(n),
/// D the energy the controller has dissipated, measured as the work its
/// damping force actually did over the motion (not predicted). When W < 0
/// the channel has delivered energy nobody put in: a damping
/// α = −W/(T·v²), capped and with v² floored as in passivity.hpp, dissipates
/// the excess over the next period. Where W ≥ 0 the channel is left alone.
///
/// Reference energy following (the credit's bound). W can grow large and
/// positive: what the loop end returned while the device end's damping or
/// its own friction absorbed it is credit that a later burst could spend at
/// once. `max_credit_j` bounds W from above (Ryu et al. 2005 let the
/// observed energy follow a reference instead of an unbounded sum): credit
/// beyond it is forgotten. 0 makes the controller act whenever this end
/// delivers more than the other end's input since the credit was last
/// spent; infinity is the plain two-port.
///
/// The loop's end's controller (admittance type, Artigas et al. 2010: at
/// the end whose output is a position). The servo loop hands the virtual
/// environment the arm's position plus an offset δ; when the loop's margin
/// W_l = E_in,remote − E_out,l + D_l is negative (the environment has taken
/// in more than the arm put in: a spring would give it back as credit) the
/// offset moves against the held force f by Δδ = −W_l/f, which returns
/// exactly the deficit (f·Δδ = −W_l, booked as D_l: energy taken from the
/// environment, never sent as E_in). Capped as a series damper would: |Δδ| ≤
/// T·|f|/max_damping, |δ| ≤ max_offset_m; with |f| below
/// max_damping·min_speed nothing can be returned. What the cap leaves is
/// the loop's `charged` (its largest uncovered deficit so far), which the
/// arm's end subtracts from E_in,loop: its controller covers the rest. While
/// W_l ≥ 0, δ drifts back to zero at min_speed at most, paid from W_l.
///
/// Over a link both ends send monotone counters (energy_in, charged): a lost
/// or reordered report is superseded by any newer one.
///
/// Allocation-free, lock-free, no logging: one per arm in the servo loop
/// (the loop's end, for a device behind a link: the udp driver, protocol
/// version 2) and one in the device's server (`haptel-device-server`, the
/// arm's end); `haptel bench passivity` runs both on its delay line too.
#include <limits>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// Which end of the channel a TwoPortPassivity observes.
enum class ChannelEnd {
  kDevice,  ///< the arm's side: position in, force out (power in = −f·v)
  kLoop,    ///< the servo loop's side: force in, position out (power in = +f·v)
};

/// The controller's limits.
struct TwoPortLimits {
  double max_damping = 20.0;  ///< N·s/m: the most damping the device renders stably
  double min_speed = 0.002;   ///< m/s: v² is floored at min_speed² in α = −W/(T·v²)
  /// J per axis: the largest margin W kept (credit beyond it is forgotten).
  double max_credit_j = std::numeric_limits<double>::infinity();
  /// m per axis: the loop's end's largest position offset (ControlPosition).
  double max_offset_m = 0.01;
};

/// What the controller did on one tick.
struct TwoPortAction {
  Vec3d damping_force{};  ///< N, to add to the rendered force: −α·v per axis
  Vec3d alpha{};          ///< N·s/m per axis (0 where W ≥ 0)
  bool acted = false;     ///< α > 0 on some axis
};

class TwoPortPassivity {
 public:
  explicit TwoPortPassivity(ChannelEnd end, const TwoPortLimits& limits = TwoPortLimits{})
      : end_(end), limits_(limits) {}

  /// Observes the period just ended: the hand moved `displacement` (m) under
  /// the force held since the last Hold (or Control). Call once per tick,
  /// before Control.
  void Observe(const Vec3d& displacement);

  /// The controller (the device end): `rendered` is the force the channel
  /// delivers now (N, on the hand), `remote_energy_in` the other end's E_in
  /// as last received (J per axis), `velocity` the hand's now (m/s).
  /// Returns the damping to add and holds both forces for the next Observe.
  TwoPortAction Control(const Vec3d& rendered, const Vec3d& remote_energy_in, const Vec3d& velocity,
                        double period_s);

  /// The loop's end's controller (admittance type, above): call once per tick
  /// after Observe, before Hold of the new force. Returns the offset δ (m per
  /// axis) to add to the arm's position wherever the virtual environment
  /// reads it this tick. `acted` (optional) is set when it moved δ to
  /// return a deficit.
  const Vec3d& ControlPosition(const Vec3d& remote_energy_in, double period_s,
                               bool* acted = nullptr);

  /// The loop's end without a controller: its deficit (−W where W < 0) is
  /// charged to the arm's end instead — `charged` keeps the largest so far
  /// (monotone, as the link carries it). Call once per tick after Observe.
  void ChargeDeficit(const Vec3d& remote_energy_in);

  /// The offset ControlPosition keeps (m per axis).
  const Vec3d& offset() const { return offset_; }
  /// J per axis: the loop's end's largest deficit left uncovered by its
  /// capped controller (monotone): sent beside E_in, charged to the arm's end.
  const Vec3d& charged() const { return charged_; }

  /// Holds the forces that will act over the next period when the caller
  /// changed them (a saturated actuator) or has no controller (the loop
  /// end): `rendered` the channel's force, `damping` the controller's (N).
  void Hold(const Vec3d& rendered, const Vec3d& damping = Vec3d{});

  /// The margin W per axis against `remote_energy_in` (J): < 0 when this end
  /// has delivered more than the other put in.
  Vec3d Margin(const Vec3d& remote_energy_in) const;

  /// What this end sends the other (J per axis): its E_in, less its own
  /// deficit (−W where W < 0) when it has no controller to dissipate it.
  /// The loop's end has none (its output is a position, which an impedance
  /// controller cannot correct); energy the channel handed the virtual
  /// environment beyond what the arm put in would otherwise come back from
  /// a spring as E_in and reach the arm as credit. Charged to the arm's end,
  /// the arm's controller keeps the whole channel passive:
  /// E_out,arm − D ≤ E_in,loop − (E_out,loop − E_in,arm), both ends' flows
  /// as they were a delay apart.
  Vec3d EnergyToSend(const Vec3d& remote_energy_in) const;

  /// Forgets everything: after the device was lost or the channel restarted
  /// (both ends must reset together; a restarted end sends zeros).
  void Reset();

  /// J per axis: what entered the channel at this end (to send), what left
  /// it here, and what this end's controller dissipated.
  const Vec3d& energy_in() const { return energy_in_; }
  const Vec3d& energy_out() const { return energy_out_; }
  const Vec3d& dissipated() const { return dissipated_; }
  /// J: dissipated() over all three axes.
  double dissipated_total_j() const { return dissipated_[0] + dissipated_[1] + dissipated_[2]; }
  const TwoPortLimits& limits() const { return limits_; }

 private:
  ChannelEnd end_;
  TwoPortLimits limits_;
  Vec3d energy_in_{};
  Vec3d energy_out_{};
  Vec3d dissipated_{};
  Vec3d forgotten_{};      ///< credit beyond max_credit_j, J
  Vec3d offset_{};         ///< m, the loop's end's position offset
  Vec3d charged_{};        ///< J, the loop's end's largest uncovered deficit
  Vec3d held_rendered_{};  ///< N, the channel's force over the coming period
  Vec3d held_damping_{};   ///< N, the controller's force over the coming period
};

}  // namespace haptel::haptics
