#pragma once
/// @file The automatic operator: a simulated person who drives the vehicle
/// through the mediator interface, as a human would.
///
/// It sees the vehicle's reported pose after a reaction delay, decides with
/// pure pursuit along the track's centre line, and expresses the decision as
/// hand targets through the interface's own inverse map. Its arm lags the
/// decision (first-order), and the simulated device's muscle model makes it
/// feel forces: a centring field must be pushed against, a wall stops it.
/// After a bumper contact it backs off, turning away from the touched side.
///
/// When the interface has controls to grasp (a hand goal with an approach
/// offset), the operator first brings its open hands down onto them over
/// `grasp_reach_s`, closes its fingers over `grasp_close_s`, and only then
/// starts driving; the interface reads the controls as they are meanwhile.
#include <deque>

#include "haptel/config/run.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::mediator {

/// What the operator perceives of the vehicle at one instant.
struct Observation {
  double t_s = 0.0;
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
  bool bumper_left = false;
  bool bumper_right = false;
};

class AutoOperator {
 public:
  /// Keeps a reference to `track`.
  AutoOperator(const Track& track, const OperatorConfig& config, const DriveConfig& drive);

  /// Something the operator saw (e.g. each vehicle state as it arrives).
  void Observe(const Observation& observation);
  /// What the operator wants at time t_s, from what it saw reaction_delay ago.
  interfaces::DriveIntent Decide(double t_s);
  /// Hand goals after the arm's lag, for the interface's inverse map. The
  /// first call starts the grasp, if the interface has anything to grasp.
  interfaces::HandTargets Act(double t_s, const interfaces::MediatorInterface& interface);

  bool backing_off(double t_s) const { return t_s < backoff_until_s_; }
  /// The hands hold their controls (or there is nothing to grasp) and the
  /// operator drives.
  bool grasped(double t_s) const {
    return start_s_ >= 0 && t_s >= start_s_ + grasp_s_;
  }

 private:
  const Track& track_;
  OperatorConfig config_;
  DriveConfig drive_;
  std::deque<Observation> seen_;
  double backoff_until_s_ = -1.0;
  double backoff_turn_ = 0.0;
  interfaces::HandTargets arm_;
  double last_act_s_ = -1.0;
  double start_s_ = -1.0;  ///< first Act
  double grasp_s_ = 0.0;   ///< reach + close, 0 when nothing is grasped
};

}  // namespace haptel::mediator
