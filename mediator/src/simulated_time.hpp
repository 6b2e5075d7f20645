#pragma once
// A session in simulated time (`haptel run --simulated-time`): every part
// the real-time session runs on its own thread or process — the servo loop's
// ticks, the physics world's steps, the vehicle's control loop — stepped in
// the session's one thread on the process's simulated clock
// (SetSimulatedNs), lock-step and in a fixed order, as fast as the CPU
// allows. Commands reach the vehicle, and its states the session, after the
// link's configured one-way delay. Internal to the mediator library.
#include <cstdint>
#include <deque>
#include <memory>

#include "haptel/link/families.hpp"
#include "haptel/mediator/haptic_side.hpp"
#include "haptel/mediator/in_process_vehicle.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/vehicle_link.hpp"

namespace haptel::mediator {

/// The simulated clock's time when a simulated-time session starts: the
/// same for every run, so that the same seed gives the same lap to the
/// tick (nothing depends on the start but through differences; a fixed
/// one keeps even their rounding alike). Past any time the set-up's own
/// simulated calibration reaches.
constexpr int64_t kSimulatedEpochNs = 1'000'000'000'000;

/// Why a setup cannot run in simulated time ("" when it can): the
/// automatic operator (or a person's run at the simulated device, whose
/// arms nobody holds), a simulated robot that steps in process, no view,
/// no recording, no vehicle attached, a link fault of a delay alone.
std::string SimulatedTimeProblem(const SessionSetup& setup);

class SimulatedTime {
 public:
  /// Puts the process on the simulated clock at kSimulatedEpochNs and makes
  /// the in-process robot (GetInProcessRobotFactory). Throws ConfigError
  /// when the setup cannot run in simulated time, std::logic_error when no
  /// factory is registered.
  explicit SimulatedTime(const SessionSetup& setup);
  /// Back to the real clock.
  ~SimulatedTime();
  SimulatedTime(const SimulatedTime&) = delete;
  SimulatedTime& operator=(const SimulatedTime&) = delete;

  /// The command sink for VehicleLinkOptions::in_process_robot: a command
  /// sent now reaches the robot one link delay later.
  void OnCommand(const msg::TreadCommand& command);
  /// Steps every part whose tick falls in (now, deadline_ns], in time order
  /// (at equal times: deliveries, servo, physics, vehicle), the clock set to
  /// each tick's time; leaves the clock at `deadline_ns`. `physics` may be
  /// null (none yet); the robot's states go into `link`'s inbox.
  void AdvanceTo(int64_t deadline_ns, HapticSide& haptic, const SessionPhysics* physics,
                 VehicleLink& link);
  /// The end: the robot made safe.
  void Stop();

  int64_t now_ns() const { return now_ns_; }
  uint64_t servo_ticks() const { return servo_ticks_; }
  uint64_t physics_ticks() const { return physics_ticks_; }
  uint64_t vehicle_ticks() const { return vehicle_ticks_; }
  double servo_period_s() const { return NsToSeconds(servo_period_ns_); }
  double physics_period_s() const { return NsToSeconds(physics_period_ns_); }

 private:
  static double NsToSeconds(int64_t ns) { return static_cast<double>(ns) * 1e-9; }
  template <typename Message>
  struct InFlight {
    int64_t due_ns;
    Message message;
  };

  Track track_;  ///< the robot's world (it keeps a reference)
  std::unique_ptr<InProcessRobot> robot_;
  int64_t delay_ns_ = 0;
  int64_t now_ns_ = kSimulatedEpochNs;
  int64_t start_ns_ = kSimulatedEpochNs;
  int64_t servo_period_ns_;
  int64_t physics_period_ns_ = 0;
  int64_t vehicle_period_ns_;
  uint64_t servo_ticks_ = 0;
  uint64_t physics_ticks_ = 0;
  uint64_t vehicle_ticks_ = 0;
  int64_t physics_start_ns_ = 0;  ///< when the world was first seen (0: not yet)
  std::deque<InFlight<msg::TreadCommand>> commands_;
  std::deque<InFlight<msg::VehicleState>> states_;
};

}  // namespace haptel::mediator
