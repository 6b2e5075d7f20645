#pragma once
/// @file The automatic operator: a simulated person who drives the vehicle
/// through the mediator interface, as a human would.
///
/// It sees the vehicle's reported pose after a reaction delay, decides with
/// pure pursuit along the track's centre line, and expresses the decision as
/// hand targets through the interface's own inverse map. Its arm lags the
/// decision (first-order), and the simulated device's muscle model makes it
/// feel forces: a centring field must be pushed against, a wall stops it.
/// After a bumper contact it backs off, turning away from the touched side,
/// then aims its next attempt: for careful_s it looks half as far ahead and
/// its steering has full attention (none of the profile's wander or
/// re-centring miss, below), along a line beside the post or obstacle it
/// hit (on the side of the corridor with more room). A new contact while aiming (the bumpers were
/// clear in between) backs it off further. A contact that outlasts its
/// back-off is not backed off again — the robot has no rear bumper, so
/// reversing further may only push it into what is behind — the operator
/// turns on the spot away from it instead: it never reverses for longer
/// than one back-off per contact, so it never backs away for good from a
/// finish it has not crossed.
///
/// It drives a vehicle that is not its model the way a careful person
/// would: it watches how much the vehicle turns for the turn it asks (the
/// heading's change between what it sees against its own decisions a
/// moment before) and steers harder by what it finds missing (a skidding
/// tank turns as a wider one; Mandow et al. 2007), and it slows down as a
/// post or obstacle comes into the band its body will sweep ahead.
///
/// When the interface has controls to grasp (a hand goal with an approach
/// offset), the operator first brings its open hands down onto them over
/// `grasp_reach_s`, closes its fingers over `grasp_close_s`, and only then
/// starts driving; the interface reads the controls as they are meanwhile.
///
/// Its DriverProfile makes it a particular person rather than the ideal
/// driver (study/: the simulated participants): steering that wanders,
/// controls that slip out of the hand and are grasped again, the effort of
/// re-centring a control that stays where it was left, a speedometer read
/// now and then, and errors that shrink with the trials done before.
#include <array>
#include <cstdint>
#include <deque>
#include <random>

#include "haptel/config/run.hpp"
#include "haptel/config/study.hpp"
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
  /// Keeps a reference to `track`. `experience`: trials this driver has done
  /// before (the profile's errors shrink with it).
  AutoOperator(const Track& track, const OperatorConfig& config, const TreadDriveConfig& drive,
               const DriverProfile& profile = {}, int experience = 0);

  /// Something the operator saw (e.g. each vehicle state as it arrives).
  void Observe(const Observation& observation);
  /// What the operator wants at time t_s, from what it saw reaction_delay ago
  /// (the ideal intent: before the profile's errors).
  interfaces::MotionIntent Decide(double t_s);
  /// The intent as this driver expresses it on `interface`: with the
  /// profile's steering wander, speed cue and re-centring; t_s increasing.
  interfaces::MotionIntent Express(double t_s, const interfaces::MotionIntent& ideal,
                                   const interfaces::MediatorInterface& interface);
  /// Hand goals after the arm's lag, for the interface's inverse map. The
  /// first call starts the grasp, if the interface has anything to grasp.
  interfaces::HandTargets Act(double t_s, const interfaces::MediatorInterface& interface);

  bool backing_off(double t_s) const { return t_s < backoff_until_s_; }
  /// Backing off, or aiming the attempt after it (config careful_s).
  bool careful(double t_s) const { return t_s < careful_until_s_; }
  /// The hands hold their controls (or there is nothing to grasp) and the
  /// operator drives.
  bool grasped(double t_s) const { return start_s_ >= 0 && t_s >= start_s_ + grasp_s_; }
  /// Times a control slipped out of a hand so far.
  int slips() const { return slips_; }
  /// The profile's error scale for this driver's experience (1: practised).
  double error_scale() const { return error_scale_; }

 private:
  const Track& track_;
  OperatorConfig config_;
  TreadDriveConfig drive_;
  struct Seen {
    Observation observation;
    uint64_t clears = 0;  ///< observations with clear bumpers up to this one
  };
  std::deque<Seen> seen_;
  uint64_t clears_ = 0;
  /// `clears` of the contact that started the last back-off (none yet: never matches).
  uint64_t backoff_clears_ = UINT64_MAX;
  double backoff_until_s_ = -1.0;
  double backoff_turn_ = 0.0;
  /// While aiming after hitting a post or an obstacle: the line it aims
  /// along, left of the centre line (m), beside what it hit; 0 after a wall.
  double aim_offset_ = 0.0;
  /// How far from the robot's centre a round obstacle ahead counts as the
  /// one it touched, m (its body's radius and more).
  static constexpr double kObstacleReach = 0.2;
  /// The aim offset that passes the round obstacle `o`'s front touches.
  double PassingOffset(const Observation& o) const;
  /// Observed against expected yaw rate while turning: the vehicle's turn
  /// response (1: the model's), and how much turning it is made of (s).
  void LearnTurnResponse(const Observation& o);
  double turn_response_ = 1.0;
  double turn_seen_s_ = 0.0;
  /// The turns decided (time, expected yaw rate rad/s), the last second's.
  std::deque<std::pair<double, double>> decided_;
  /// The forward share allowed by the nearest round obstacle in the band
  /// the body sweeps ahead (1: none near).
  double ObstacleSlowdown(const Observation& o) const;
  double careful_until_s_ = -1.0;
  int repeat_contacts_ = 0;  ///< contacts in a row, each while aiming after the last
  interfaces::HandTargets arm_;
  double last_act_s_ = -1.0;
  double start_s_ = -1.0;  ///< first Act
  double grasp_s_ = 0.0;   ///< reach + close, 0 when nothing is grasped

  // The profile's state (all inert for the ideal driver).
  /// A profile's speed factor at this driver's experience (its shortfall
  /// from 1 scaled like the other errors).
  double Practised(double factor) const;
  /// Draws the next slip of hand i after t_s (never, without slips).
  void ScheduleSlip(size_t i, double t_s);
  DriverProfile profile_;
  double error_scale_ = 1.0;
  std::mt19937_64 random_;
  double reaction_s_;  ///< reaction delay: the config's, plus the profile's while holding controls
  double wander_ = 0.0;  ///< the steering's Ornstein–Uhlenbeck state
  double last_express_s_ = -1.0;
  interfaces::MotionIntent applied_;     ///< the intent on controls that stay put
  std::array<double, 2> centre_miss_{};  ///< forward, turn: where "centre" ends up
  std::array<bool, 2> at_centre_{true, true};
  std::array<double, 2> slip_start_s_{-1.0, -1.0};  ///< per hand; < 0: holding
  std::array<double, 2> next_slip_s_{-1.0, -1.0};   ///< per hand; < 0: not scheduled
  int slips_ = 0;
};

}  // namespace haptel::mediator
