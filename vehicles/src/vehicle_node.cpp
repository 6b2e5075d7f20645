#include "haptel/vehicles/vehicle_node.hpp"

#include "haptel/link/fault_transport.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"

namespace haptel::vehicles {

template <class Family>
VehicleNodeOf<Family>::VehicleNodeOf(const VehicleConfig& config, std::unique_ptr<video::CameraSource> camera,
                                     std::unique_ptr<Adapter> adapter)
    : config_(Validated(config)), adapter_(std::move(adapter)), commands_(config.watchdog_timeout_s) {
  if (adapter_ == nullptr) throw std::invalid_argument("vehicle node: no adapter");
  if (camera == nullptr) throw std::invalid_argument("vehicle node: no camera source");
  ticks_per_state_ = std::max(1, static_cast<int>(std::lround(config.sim_rate_hz / config.state_rate_hz)));
  Family::Prepare(*adapter_);

  participant_ = std::make_unique<link::Participant>(config.link, "haptel-vehicle-" + config.name);
  state_writer_ = std::make_unique<typename Family::StateWriter>(
      *participant_, link::TopicName(config.name, "state"), link::Profile::kState);
  camera_ = std::make_unique<CameraStreamer>(config.camera, std::move(camera), *participant_, config.name);
  camera_->SetPose(Family::CameraPoseOf(adapter_->State()));
  command_reader_ = std::make_unique<typename Family::CommandReader>(
      *participant_, link::TopicName(config.name, "command"), link::Profile::kCommand,
      [this](const typename Family::CommandMsg& cmd) { OnCommand(cmd); });
  control_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-control", .rate_hz = config.sim_rate_hz},
      [this](int64_t now) { ControlTick(now); });
}

template <class Family>
VehicleNodeOf<Family>::~VehicleNodeOf() {
  Stop();
}

template <class Family>
void VehicleNodeOf<Family>::Start() {
  control_->Start();
  camera_->Start();
}

template <class Family>
void VehicleNodeOf<Family>::Stop() {
  if (stopped_.exchange(true)) return;
  camera_->Stop();
  control_->Stop();
  if (!failed_.load()) {
    try {
      Family::MakeSafe(*adapter_);
      adapter_->Update(1e-3);
    } catch (const cli::HardwareLost&) {
      // The bus or port is gone: nothing more can be sent; the hardware's own
      // time-out (a servo controller's serial timeout, an ODrive's watchdog)
      // makes it safe.
    }
  }
  PublishState(MonotonicNs());
}

template <class Family>
void VehicleNodeOf<Family>::OnCommand(const typename Family::CommandMsg& cmd) {
  typename Family::Command command;
  const bool valid = Family::Decode(cmd, command);
  commands_.Offer(valid, {cmd.session(), cmd.operator_name().c_str(), cmd.release()}, cmd.seq(), cmd.sent_ns(),
                  command, MonotonicNs());
}

template <class Family>
void VehicleNodeOf<Family>::ControlTick(int64_t now_ns) {
  if (failed_.load(std::memory_order_relaxed)) return;
  const bool expired = commands_.Poll(now_ns);
  const double dt = ControlStep(last_tick_ns_, now_ns, config_.sim_rate_hz);
  try {
    if (expired) {
      Family::MakeSafe(*adapter_);
    } else {
      Family::Apply(*adapter_, commands_.applied().command, config_);
    }
    adapter_->Update(dt);
  } catch (const cli::HardwareLost& e) {
    // A port or bus that vanished: stop driving it and say so once; the
    // node's owner ends the process (exit 3).
    failure_ = e.what();
    failed_.store(true);
    return;
  }
  camera_->SetPose(Family::CameraPoseOf(adapter_->State()));
  if (tick_count_++ % static_cast<uint64_t>(ticks_per_state_) == 0) PublishState(now_ns);
}

template <class Family>
void VehicleNodeOf<Family>::PublishState(int64_t now_ns) {
  const typename Family::AdapterState s = adapter_->State();
  typename Family::StateMsg& m = state_msg_;
  m.seq(++state_seq_);
  m.stamp_ns(now_ns);
  Family::FillState(s, commands_.watchdog_expired(), m);
  m.last_command_seq(commands_.applied().seq);
  m.last_command_sent_ns(commands_.applied().sent_ns);
  m.last_command_age_ns(commands_.AppliedAgeNs(now_ns));
  m.commands_received(commands_.accepted());
  const CommandOwnerInfo owner = commands_.owner();
  m.owner_session(owner.session);
  m.owner(owner.name);
  m.commands_refused(commands_.refused());
  if (s.fault && !faulted_.load()) {
    fault_ = s.fault_message;
    faulted_.store(true);
  }
  const bool failed = failed_.load();
  m.fault(s.fault || failed);
  m.fault_message(failed ? failure_ : s.fault_message);
  state_writer_->Write(m);
  states_.fetch_add(1, std::memory_order_relaxed);
}

template <class Family>
NodeCounters VehicleNodeOf<Family>::Counters() const {
  NodeCounters c = MakeNodeCounters(commands_, camera_->Counters(), states_.load());
  if (const link::FaultLine* line = participant_->fault_line()) {
    const link::FaultCounts fault = line->Counts();
    c.link_queue_dropped = fault.queue_dropped;
    c.link_queue_dropped_bytes = fault.queue_dropped_bytes;
  }
  return c;
}

template <class Family>
std::string VehicleNodeOf<Family>::AdapterFailure() const {
  return failed_.load() ? failure_ : std::string();
}

template <class Family>
std::string VehicleNodeOf<Family>::Fault() const {
  return faulted_.load() ? fault_ : std::string();
}

template class VehicleNodeOf<RobotFamily>;
template class VehicleNodeOf<BlimpFamily>;

}  // namespace haptel::vehicles
