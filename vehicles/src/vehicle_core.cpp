#include "haptel/vehicles/vehicle_core.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/process_identity.hpp"

namespace haptel::vehicles {

template <class Family>
VehicleCoreOf<Family>::VehicleCoreOf(const VehicleConfig& config, std::unique_ptr<Adapter> adapter)
    : config_(Validated(config)),
      adapter_(std::move(adapter)),
      commands_(config.watchdog_timeout_s) {
  if (adapter_ == nullptr) throw std::invalid_argument("vehicle node: no adapter");
  ticks_per_state_ =
      std::max(1, static_cast<int>(std::lround(config.sim_rate_hz / config.state_rate_hz)));
  // Who publishes: set once, every state carries it (the message is reused).
  state_msg_.vehicle_pid(static_cast<int64_t>(getpid()));
  state_msg_.vehicle_host(HostName());
  Family::Prepare(*adapter_);
  if (const DrawnReality* reality = adapter_->reality()) {
    clock_offset_ns_ = SToNs(reality->clock_offset_s);
    clock_drift_ = reality->clock_drift_ppm * 1e-6;
  }
  if (!config_.truth_file.empty()) {
    const DrawnReality* reality = adapter_->reality();
    if (reality == nullptr) {
      throw ConfigError(config_.file.string() + ": kind '" + config_.kind +
                        "' has no truth to record (only a simulated vehicle knows where it "
                        "truly is); expected no truth record (--truth)");
    }
    truth_ = std::make_unique<TruthWriter>(config_.truth_file, *reality);
  }
}

template <class Family>
void VehicleCoreOf<Family>::OnCommand(const typename Family::CommandMsg& cmd,
                                      const link::WriterId& writer, int64_t now_ns) {
  Command command;
  const bool valid = Family::Decode(cmd, command);
  commands_.Offer(valid, {writer, cmd.session(), cmd.operator_name().c_str(), cmd.release()},
                  cmd.seq(), cmd.sent_ns(), command, now_ns);
}

template <class Family>
bool VehicleCoreOf<Family>::ControlTick(int64_t now_ns) {
  state_due_ = false;
  if (failed_.load(std::memory_order_relaxed)) return false;
  const uint64_t applied_seq = commands_.applied().seq;
  const int64_t tick_before_ns = last_tick_ns_;
  const bool expired = commands_.Poll(now_ns);
  const double dt = ControlStep(last_tick_ns_, now_ns, config_.sim_rate_hz);
  // A simulated world moves on under the command it had until a new one
  // came (applied from the last tick on, a late tick's command would act a
  // stall's length early; the truth and the predictor's replay then part).
  double before_s = 0.0;
  if (adapter_->reality() != nullptr && tick_before_ns != 0 &&
      commands_.applied().seq != applied_seq) {
    before_s = std::clamp(NsToS(commands_.applied().received_ns - tick_before_ns), 0.0, dt);
  }
  try {
    if (before_s > 0.0) adapter_->Update(before_s);
    if (expired) {
      Family::MakeSafe(*adapter_);
    } else {
      Family::Apply(*adapter_, commands_.applied().command, config_);
    }
    adapter_->Update(dt - before_s);
    if (first_tick_ns_ == 0) first_tick_ns_ = now_ns;
    if (truth_) {
      TruthRow row;
      if (adapter_->Truth(&row)) {
        row.operator_ns = now_ns;
        truth_->Write(row);
      }
    }
  } catch (const cli::HardwareLost& e) {
    // A port or bus that vanished: stop driving it and say so once; the
    // node's owner ends the process (exit 3).
    failure_ = e.what();
    failed_.store(true);
    return false;
  }
  state_due_ = tick_count_++ % static_cast<uint64_t>(ticks_per_state_) == 0;
  return true;
}

template <class Family>
typename Family::StateMsg& VehicleCoreOf<Family>::MakeState(int64_t now_ns) {
  const typename Family::AdapterState s = adapter_->State();
  typename Family::StateMsg& m = state_msg_;
  m.seq(++state_seq_);
  const int64_t measured_ns = now_ns - SToNs(s.measured_age_s);
  const int64_t since_ns = first_tick_ns_ != 0 ? measured_ns - first_tick_ns_ : 0;
  m.stamp_ns(measured_ns + clock_offset_ns_ +
             static_cast<int64_t>(clock_drift_ * static_cast<double>(since_ns)));
  Family::FillState(s, commands_.watchdog_expired(), m);
  m.last_command_seq(commands_.applied().seq);
  m.last_command_sent_ns(commands_.applied().sent_ns);
  m.last_command_age_ns(commands_.AppliedAgeNs(now_ns));
  m.commands_received(commands_.accepted());
  const CommandOwnerInfo owner = commands_.owner();
  m.owner_session(owner.session);
  m.owner(owner.name);
  m.owner_writer(owner.writer.guid);
  m.commands_refused(commands_.refused());
  if (s.fault && !faulted_.load()) {
    fault_ = s.fault_message;
    faulted_.store(true);
  }
  const bool failed = failed_.load();
  m.fault(s.fault || failed);
  m.fault_message(failed ? failure_ : s.fault_message);
  return m;
}

template <class Family>
void VehicleCoreOf<Family>::MakeSafe() {
  if (failed_.load()) return;
  try {
    Family::MakeSafe(*adapter_);
    adapter_->Update(1e-3);
  } catch (const cli::HardwareLost&) {
    // The bus or port is gone: nothing more can be sent; the hardware's own
    // time-out (a servo controller's serial timeout, an ODrive's watchdog)
    // makes it safe.
  }
}

template <class Family>
std::string VehicleCoreOf<Family>::AdapterFailure() const {
  return failed_.load() ? failure_ : std::string();
}

template <class Family>
std::string VehicleCoreOf<Family>::Fault() const {
  return faulted_.load() ? fault_ : std::string();
}

template class VehicleCoreOf<RobotFamily>;
template class VehicleCoreOf<BlimpFamily>;

}  // namespace haptel::vehicles
