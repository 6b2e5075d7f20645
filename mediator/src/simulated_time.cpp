#include "simulated_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/haptics/device_drivers.hpp"

namespace haptel::mediator {

namespace {

InProcessRobotFactory& Factory() {
  static InProcessRobotFactory factory;
  return factory;
}

/// A rate's period in whole ns (every tick lands on the same ns in every run).
int64_t PeriodNs(double rate_hz) { return std::max<int64_t>(1, std::llround(1e9 / rate_hz)); }

}  // namespace

void SetInProcessRobotFactory(InProcessRobotFactory factory) { Factory() = std::move(factory); }
const InProcessRobotFactory& GetInProcessRobotFactory() { return Factory(); }

std::string SimulatedTimeProblem(const SessionSetup& setup) {
  // A person's run at the simulated arms has nobody at them: nothing
  // happens in it that needs a person's time (it shows that nothing moves).
  if (setup.operator_kind != "auto" && !haptics::DriverOf(setup.device).simulated) {
    return "the automatic operator drives a simulated-time run (a person drives in real time); use "
           "--operator auto";
  }
  const VehicleKindInfo* kind = FindVehicleKind(setup.vehicle.kind);
  if (kind == nullptr || !kind->steps_in_process ||
      setup.vehicle.family() != VehicleFamily::kRobot) {
    std::string simulated;
    for (const VehicleKindInfo& k : VehicleKinds()) {
      if (k.steps_in_process && k.family == VehicleFamily::kRobot)
        simulated += (simulated.empty() ? "" : ", ") + k.name;
    }
    return "vehicle '" + setup.vehicle.file.string() + "' is of kind '" + setup.vehicle.kind +
           "', which does not step in this process; a simulated-time run needs a simulated robot "
           "(kind " +
           simulated + "), e.g. --vehicle config/vehicles/sim-robot.yaml";
  }
  if (setup.attach)
    return "--attach drives a vehicle running elsewhere, in real time; a simulated-time run spawns "
           "its own";
  if (setup.view != ViewKind::kNone || !setup.record.empty()) {
    return "a simulated-time run has no view (it runs faster than a person could watch); use "
           "--view none and no --record";
  }
  const LinkFault& fault = setup.run.link.fault;
  if (fault.enabled && (fault.jitter_s > 0.0 || fault.loss > 0.0 || fault.rate_bps > 0.0)) {
    return "a simulated-time run models the link's delay alone; the link fault '" +
           LinkFaultText(fault) + "' also has jitter, loss or a rate: keep only delay=";
  }
  return "";
}

SimulatedTime::SimulatedTime(const SessionSetup& setup)
    : track_(setup.track),
      servo_period_ns_(PeriodNs(setup.device.servo.rate_hz)),
      vehicle_period_ns_(1) {
  if (const std::string problem = SimulatedTimeProblem(setup); !problem.empty()) {
    throw ConfigError("--simulated-time: " + problem);
  }
  const InProcessRobotFactory& factory = GetInProcessRobotFactory();
  if (!factory)
    throw std::logic_error(
        "--simulated-time: this program cannot step a vehicle in its own process");
  if (setup.run.link.fault.enabled) delay_ns_ = SToNs(setup.run.link.fault.delay_s);
  SetSimulatedNs(now_ns_);
  robot_ = factory(setup.vehicle, track_);
  vehicle_period_ns_ = PeriodNs(robot_->control_rate_hz());
}

SimulatedTime::~SimulatedTime() { StopSimulatedClock(); }

void SimulatedTime::OnCommand(const msg::TreadCommand& command) {
  commands_.push_back({now_ns_ + delay_ns_, command});
}

void SimulatedTime::AdvanceTo(int64_t deadline_ns, HapticSide& haptic,
                              const SessionPhysics* physics, VehicleLink& link) {
  if (physics != nullptr && physics_start_ns_ == 0) {
    // A world built now steps from now on, at its own fixed step.
    physics_start_ns_ = now_ns_;
    physics_period_ns_ = PeriodNs(1.0 / physics->world->config().step_s);
  }
  constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  for (;;) {
    const int64_t next_servo =
        start_ns_ + static_cast<int64_t>(servo_ticks_ + 1) * servo_period_ns_;
    const int64_t next_vehicle =
        start_ns_ + static_cast<int64_t>(vehicle_ticks_ + 1) * vehicle_period_ns_;
    const int64_t next_physics =
        physics_start_ns_ != 0
            ? physics_start_ns_ + static_cast<int64_t>(physics_ticks_ + 1) * physics_period_ns_
            : kNever;
    const int64_t next_command = commands_.empty() ? kNever : commands_.front().due_ns;
    const int64_t next_state = states_.empty() ? kNever : states_.front().due_ns;
    const int64_t t = std::min({next_servo, next_vehicle, next_physics, next_command, next_state});
    if (t > deadline_ns) break;
    now_ns_ = t;
    SetSimulatedNs(t);
    // What the link delivers now, first: the vehicle and the session see it this tick.
    while (!commands_.empty() && commands_.front().due_ns <= t) {
      robot_->OnCommand(commands_.front().message, t);
      commands_.pop_front();
    }
    while (!states_.empty() && states_.front().due_ns <= t) {
      link.channel<link::RobotMessages>().Deliver(states_.front().message);
      states_.pop_front();
    }
    if (next_servo == t) {
      haptic.Tick(t);
      ++servo_ticks_;
    }
    if (next_physics == t) {
      physics->world->Tick(haptic.hal(), t);
      ++physics_ticks_;
    }
    if (next_vehicle == t) {
      ++vehicle_ticks_;
      if (const msg::VehicleState* state = robot_->Tick(t))
        states_.push_back({t + delay_ns_, *state});
    }
  }
  now_ns_ = deadline_ns;
  SetSimulatedNs(deadline_ns);
}

void SimulatedTime::Stop() {
  // The commands still on their way arrive first, as they would.
  for (const auto& c : commands_) robot_->OnCommand(c.message, now_ns_);
  commands_.clear();
  robot_->MakeSafe();
}

}  // namespace haptel::mediator
