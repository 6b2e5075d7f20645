#include "haptel/vehicles/vehicle_node.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/fault_transport.hpp"

namespace haptel::vehicles {

template <class Family>
VehicleNodeOf<Family>::VehicleNodeOf(const VehicleConfig& config,
                                     std::unique_ptr<video::CameraSource> camera,
                                     std::unique_ptr<Adapter> adapter,
                                     std::unique_ptr<KindReport> report)
    : core_(config, std::move(adapter)) {
  if (camera == nullptr) throw std::invalid_argument("vehicle node: no camera source");
  const VehicleConfig& c = core_.config();
  participant_ = std::make_unique<link::Participant>(c.link, "haptel-vehicle-" + c.name);
  state_writer_ = std::make_unique<typename Family::StateWriter>(
      *participant_, link::TopicName(c.name, "state"), link::Profile::kState);
  report_ = std::move(report);
  if (report_) report_->Open(*participant_, c.name);
  camera_ =
      std::make_unique<video::CameraStreamer>(c.camera, std::move(camera), *participant_, c.name,
                                              [this] { return core_.commands().owner().writer; });
  camera_->SetPose(Family::CameraPoseOf(core_.adapter().State()));
  command_reader_ = std::make_unique<typename Family::CommandReader>(
      *participant_, link::TopicName(c.name, "command"), link::Profile::kCommand,
      [this](const typename Family::CommandMsg& cmd, const link::WriterId& writer) {
        core_.OnCommand(cmd, writer, MonotonicNs());
      });
  control_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-control", .rate_hz = c.sim_rate_hz},
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
  core_.MakeSafe();
  PublishState(MonotonicNs());
}

template <class Family>
void VehicleNodeOf<Family>::ControlTick(int64_t now_ns) {
  if (!core_.ControlTick(now_ns)) return;
  camera_->SetPose(Family::CameraPoseOf(core_.adapter().State()));
  if (core_.state_due()) PublishState(now_ns);
}

template <class Family>
void VehicleNodeOf<Family>::PublishState(int64_t now_ns) {
  typename Family::StateMsg& state = core_.MakeState(now_ns);
  state.video_feedback_refused(camera_->feedback_refused());
  state_writer_->Write(state);
  states_.fetch_add(1, std::memory_order_relaxed);
  if (report_) report_->Publish();
}

template <class Family>
NodeCounters VehicleNodeOf<Family>::Counters() const {
  NodeCounters c = MakeNodeCounters(core_.commands(), camera_->Counters(), states_.load());
  if (const link::FaultLine* line = participant_->fault_line()) {
    const link::FaultCounts fault = line->Counts();
    c.link_queue_dropped = fault.queue_dropped;
    c.link_queue_dropped_bytes = fault.queue_dropped_bytes;
  }
  return c;
}

template <class Family>
std::string VehicleNodeOf<Family>::AdapterFailure() const {
  return core_.AdapterFailure();
}

template <class Family>
std::string VehicleNodeOf<Family>::Fault() const {
  return core_.Fault();
}

template class VehicleNodeOf<RobotFamily>;
template class VehicleNodeOf<BlimpFamily>;

}  // namespace haptel::vehicles
