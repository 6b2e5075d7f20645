#pragma once
/// @file A simulated robot stepped in the operator's own process, for
/// `haptel run --simulated-time`: the vehicle node's control step (its
/// command intake, watchdog, adapter and state message, vehicles'
/// VehicleCoreOf) without DDS or a thread, ticked on the run's simulated
/// clock. The mediator does not link the vehicles' nodes (DESIGN: the two
/// talk only through link's messages), so the program that links both
/// (`haptel`'s main) registers the factory.
#include <cstdint>
#include <functional>
#include <memory>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/link/families.hpp"

namespace haptel::mediator {

class InProcessRobot {
 public:
  virtual ~InProcessRobot() = default;
  /// The control loop's rate (the vehicle file's sim_rate_hz): Tick is
  /// called at it.
  virtual double control_rate_hz() const = 0;
  /// A command message as it arrives at the vehicle, at `now_ns`.
  virtual void OnCommand(const msg::TreadCommand& command, int64_t now_ns) = 0;
  /// One control tick at `now_ns`; the state it publishes (valid until the
  /// next call), or null on a tick that publishes none.
  virtual const msg::VehicleState* Tick(int64_t now_ns) = 0;
  /// The end: motors stopped.
  virtual void MakeSafe() = 0;
};

/// Makes the in-process robot of a vehicle file (whose kind steps in
/// process, VehicleKindInfo::steps_in_process) on `track` (kept by
/// reference). Throws ConfigError for one it cannot make.
using InProcessRobotFactory = std::function<std::unique_ptr<InProcessRobot>(
    const VehicleConfig& vehicle, const Track& track)>;

/// Registered once at start-up, before any run (haptel's main).
void SetInProcessRobotFactory(InProcessRobotFactory factory);
/// The factory registered (empty: none; a program without the vehicles).
const InProcessRobotFactory& GetInProcessRobotFactory();

}  // namespace haptel::mediator
