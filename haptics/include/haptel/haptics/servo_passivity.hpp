#pragma once
/// @file One arm's passivity bookkeeping in the servo loop, apart from the
/// force composition it watches.
///
/// A local device (or one whose far end has not reported yet) gets the
/// one-port controllers (passivity.hpp) on the wrist's two ports: the
/// interface's force field, and the physics thread's proxy coupling with its
/// direct force. A device behind a link (Device::HasLink, with
/// `servo.passivity` on) gets the two-port's loop end (twoport.hpp) as well:
/// it observes what crossed the channel, charges or dissipates its deficit,
/// and sends its report with the commands; the far end's reports are kept
/// here, with its counts summed over the link's restarts.
///
/// The servo loop calls it in a tick's order: ObserveLink once the reading is
/// in, DampPorts on the forces composed from the set-point, ReportLink with
/// the wrist force the safety let through. Like the loop, it allocates
/// nothing, takes no lock and logs nothing: it counts in ServoCounters.
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/haptics/device.hpp"
#include "haptel/haptics/passivity.hpp"
#include "haptel/haptics/twoport.hpp"

namespace haptel::haptics {

struct ServoCounters;

class ArmPassivity {
 public:
  ArmPassivity() = default;
  /// `observe_link`: the device is behind a link and `servo.passivity` is on.
  ArmPassivity(const ServoLoopConfig& servo, bool observe_link);

  /// The arm is lost: the ports forget their history, and both ends of the
  /// link count afresh once the arm is back.
  void OnLost(Device& device, Side side);

  /// The two-port's loop end over the period just ended: what crossed the
  /// channel (`displacement`, m), and, when the far end reports (then the
  /// two-port runs this tick instead of the one-port ports), its deficit
  /// charged or, with `passivity_link: admittance`, the offset added to
  /// `position` that returns it to the environment. Nothing without a link.
  void ObserveLink(Device& device, Side side, const Vec3d& displacement, double period_s,
                   Vec3d& position, ServoCounters& counters);

  /// The one-port ports (with `servo.passivity` on and no far end reporting
  /// this tick): adds to `force` the damping that keeps each of the `field`
  /// and `coupling` ports (N) from generating energy.
  void DampPorts(const Vec3d& field, const Vec3d& coupling, const Vec3d& displacement,
                 const Vec3d& velocity, double period_s, Vec3d& force, ServoCounters& counters);

  /// The `wrist` force (N) held over the next period, and the loop end's
  /// report the commands carry. Nothing without a link.
  void ReportLink(Device& device, Side side, const Vec3d& wrist, const ServoCounters& counters);

  /// The one-port observers' energy now, J, summed over both ports and the
  /// axes (< 0: the virtual side generated energy); 0 with passivity off.
  double energy_j() const {
    double e = 0.0;
    for (int i = 0; i < 3; ++i) e += field_port_.energy()[i] + coupling_port_.energy()[i];
    return e;
  }

 private:
  bool one_port_ = false;        ///< `servo.passivity`
  bool observe_link_ = false;    ///< and a device behind a link
  bool admittance_ = false;      ///< `servo.passivity_link: admittance`
  bool link_reporting_ = false;  ///< this tick: the far end reported
  PassivityController field_port_;
  PassivityController coupling_port_;
  TwoPortPassivity link_end_{ChannelEnd::kLoop};  ///< the loop's end across a device's link
  LinkEnergy link_remote_;                        ///< the far end's newest report
  uint64_t link_base_ticks_ = 0;  ///< the device end's counts before the link's last restart
  double link_base_dissipated_j_ = 0.0;
};

}  // namespace haptel::haptics
