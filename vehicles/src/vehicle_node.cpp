#include "haptel/vehicles/vehicle_node.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/cli.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/link/fault_transport.hpp"

namespace haptel::vehicles {
namespace {

/// The control loop's SCHED_FIFO priority, earned and lost as every
/// PeriodicThread's (core/periodic_thread.hpp): it applies the commands,
/// runs the watchdog and sends the states. At normal priority on a loaded
/// host (a simulated twin beside the operator's processes) it waited for
/// the CPU long enough to hold a command past its time and stop on the
/// watchdog. Below the operator side's loops (servo 80, physics 70,
/// session 60): on a shared host the operator's hand comes first.
constexpr int kControlPriority = 50;

}  // namespace

template <class Family>
VehicleNodeOf<Family>::VehicleNodeOf(
    const VehicleConfig& config, std::unique_ptr<video::CameraSource> camera,
    std::unique_ptr<Adapter> adapter, std::unique_ptr<KindReport> report,
    std::vector<std::unique_ptr<video::CameraSource>> extra_cameras)
    : core_(config, std::move(adapter)) {
  if (camera == nullptr) throw std::invalid_argument("vehicle node: no camera source");
  const VehicleConfig& c = core_.config();
  participant_ = std::make_unique<link::Participant>(c.link, "haptel-vehicle-" + c.name);
  state_writer_ = std::make_unique<typename Family::StateWriter>(
      *participant_, link::TopicName(c.name, "state"), link::Profile::kState);
  report_ = std::move(report);
  if (report_) report_->Open(*participant_, c.name);
  if (extra_cameras.size() != c.extra_cameras.size()) {
    throw std::invalid_argument("vehicle node: " + std::to_string(c.extra_cameras.size()) +
                                " further cameras configured, " +
                                std::to_string(extra_cameras.size()) + " sources given");
  }
  // One camera follows its receiver's estimate as it always did; several
  // share the link by priority.
  if (!c.extra_cameras.empty()) share_ = std::make_unique<video::LinkShare>();
  camera_ = std::make_unique<video::CameraStreamer>(
      c.camera, std::move(camera), *participant_, c.name,
      [this] { return core_.commands().owner().writer; }, true, share_.get());
  camera_->SetPose(Family::CameraPoseOf(core_.adapter().State()));
  for (size_t i = 0; i < c.extra_cameras.size(); ++i) {
    auto rig = std::make_unique<CameraRig>();
    CameraRig& r = *rig;
    r.index = i + 1;
    r.config = c.extra_cameras[i];
    r.range = r.config.Range();
    r.shown.Store(Clamped(CameraAim{}, r.range));
    if (extra_cameras[i] == nullptr) throw std::invalid_argument("vehicle node: no camera source");
    // Its feedback from its holder's participant (anybody's while nobody
    // holds it, or once the holder's lease ran out).
    r.streamer = std::make_unique<video::CameraStreamer>(
        r.config, std::move(extra_cameras[i]), *participant_, c.name,
        [&r] { return r.commands.OwnerAt(MonotonicNs()).writer; }, false, share_.get());
    rigs_.push_back(std::move(rig));
  }
  if (!rigs_.empty()) {
    camera_status_ = std::make_unique<link::CameraStatusWriter>(
        *participant_, link::CameraStatusTopic(c.name), link::CameraMessages::kStatusProfile);
    for (auto& rig : rigs_) {
      CameraRig& r = *rig;
      r.reader = std::make_unique<link::CameraCommandReader>(
          *participant_, link::CameraCommandTopic(c.name, r.config.name),
          link::CameraMessages::kCommandProfile,
          [this, &r](const msg::CameraCommand& cmd, const link::WriterId& writer) {
            OnCameraCommand(r, cmd, writer);
          });
    }
    ShowCameras();
  }
  if (!rigs_.empty()) {
    camera_holders_.rigs = &rigs_;
    core_.SetDrivingBar(&camera_holders_);
  }
  command_reader_ = std::make_unique<typename Family::CommandReader>(
      *participant_, link::TopicName(c.name, "command"), link::Profile::kCommand,
      [this](const typename Family::CommandMsg& cmd, const link::WriterId& writer) {
        core_.OnCommand(cmd, writer, MonotonicNs());
      });
  control_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-control",
                              .rate_hz = c.sim_rate_hz,
                              .realtime_priority = kControlPriority},
      [this](int64_t now) { ControlTick(now); });
}

template <class Family>
VehicleNodeOf<Family>::~VehicleNodeOf() {
  Stop();
}

template <class Family>
void VehicleNodeOf<Family>::OnCameraCommand(CameraRig& r, const msg::CameraCommand& cmd,
                                            const link::WriterId& writer) {
  CameraAim aim;
  const bool valid = link::CameraMessages::Decode(cmd, r.config.name, r.range, aim);
  const uint64_t holder_before = r.commands.owner().session;
  const link::WriterId writer_before = r.commands.owner().writer;
  const int64_t now_ns = MonotonicNs();
  if (r.commands.Offer(valid, {writer, cmd.session(), cmd.operator_name().c_str(), cmd.release()},
                       cmd.seq(), cmd.sent_ns(), aim, now_ns)) {
    r.last_seq.store(cmd.seq(), std::memory_order_relaxed);
  }
  const CommandOwnerInfo now = r.commands.owner();
  if (now.writer != writer_before || now.session != holder_before)
    r.held_since_wall_ns.store(now.writer.empty() ? 0 : WallNs(), std::memory_order_relaxed);
}

template <class Family>
void VehicleNodeOf<Family>::AimCameras() {
  for (auto& rig : rigs_) {
    CameraRig& r = *rig;
    r.commands.Poll(MonotonicNs());  // the newest aim; its watchdog moves nothing
    const ReceivedCommand<CameraAim>& applied = r.commands.applied();
    if (applied.seq != 0) Family::AimCamera(core_.adapter(), r.index, applied.command);
  }
}

template <class Family>
void VehicleNodeOf<Family>::ShowCameras() {
  const video::CameraPose body = Family::CameraPoseOf(core_.adapter().State());
  for (auto& rig : rigs_) {
    CameraRig& r = *rig;
    const ReceivedCommand<CameraAim>& applied = r.commands.applied();
    CameraAim shown = applied.seq != 0 ? applied.command : r.shown.Load();
    // Where its servos hold it, where it has them (read back after the tick
    // that sent them): the picture shows what the vehicle did.
    Family::CameraAimed(core_.adapter(), r.index, &shown);
    r.shown.Store(shown);
    video::CameraPose pose = video::MountedPose(body, r.config, shown);
    pose.command_seq = applied.seq;
    r.streamer->SetPose(pose);
  }
}

template <class Family>
void VehicleNodeOf<Family>::PublishCameras(int64_t now_ns) {
  // When a camera's aim or holder changed (a holder silent for its lease,
  // CommandOwner::kFreeAfter_s, is named no more), and once a second.
  uint64_t sum = 0;
  for (const auto& rig : rigs_) {
    sum = sum * 31 + rig->last_seq.load() + rig->commands.OwnerAt(now_ns).session * 7 +
          static_cast<uint64_t>(rig->held_since_wall_ns.load());
  }
  if (sum == camera_status_sum_ && now_ns - camera_status_ns_ < 1'000'000'000) return;
  camera_status_sum_ = sum;
  camera_status_ns_ = now_ns;
  msg::CameraStatus& m = camera_status_msg_;
  m.seq(++camera_status_seq_);
  m.stamp_ns(now_ns);
  m.family(ToString(Family::kFamily));
  m.cameras().resize(rigs_.size() + 1);
  const auto fill = [&](msg::CameraInfo& info, const CameraConfig& c, bool driven) {
    info.name(c.name);
    info.video_topic(link::VideoTopic(core_.config().name, c.name, driven));
    info.driven(driven);
    info.width(static_cast<uint16_t>(c.width));
    info.height(static_cast<uint16_t>(c.height));
    info.rate_hz(static_cast<float>(c.rate_hz));
    info.codec(CameraCodecName(c.codec));
    info.priority(static_cast<uint16_t>(c.priority));
    info.fov_deg(static_cast<float>(c.fov_deg));
    const CameraRange r = c.Range();
    info.pan_min(static_cast<float>(r.pan_min));
    info.pan_max(static_cast<float>(r.pan_max));
    info.tilt_min(static_cast<float>(r.tilt_min));
    info.tilt_max(static_cast<float>(r.tilt_max));
    info.zoom_max(static_cast<float>(r.zoom_max));
  };
  fill(m.cameras()[0], core_.config().camera, true);
  m.cameras()[0].zoom(1.0F);
  for (size_t i = 0; i < rigs_.size(); ++i) {
    CameraRig& r = *rigs_[i];
    msg::CameraInfo& info = m.cameras()[i + 1];
    fill(info, r.config, false);
    const CameraAim shown = r.shown.Load();
    info.pan(static_cast<float>(shown.pan));
    info.tilt(static_cast<float>(shown.tilt));
    info.zoom(static_cast<float>(shown.zoom));
    info.last_command_seq(r.last_seq.load());
    info.commands_received(r.commands.accepted());
    info.commands_refused(r.commands.refused());
    info.commands_malformed(r.commands.malformed());
    const CommandOwnerInfo holder = r.commands.OwnerAt(now_ns);
    info.holder_session(holder.session);
    info.holder(holder.name);
    info.holder_writer(holder.writer.guid);
    info.held_since_wall_ns(holder.writer.empty() ? 0 : r.held_since_wall_ns.load());
    info.holder_heard_wall_ns(holder.writer.empty() ? 0 : r.commands.owner_heard_wall_ns());
    info.target_kbps(share_ ? share_->TargetFor(static_cast<int>(i + 1), now_ns) : 0U);
  }
  if (share_) m.cameras()[0].target_kbps(share_->TargetFor(0, now_ns));
  camera_status_->Write(m);
}

template <class Family>
void VehicleNodeOf<Family>::Start() {
  control_->Start();
  camera_->Start();
  for (auto& rig : rigs_) rig->streamer->Start();
}

template <class Family>
void VehicleNodeOf<Family>::Stop() {
  if (stopped_.exchange(true)) return;
  for (auto& rig : rigs_) rig->streamer->Stop();
  camera_->Stop();
  control_->Stop();
  core_.MakeSafe();
  PublishState(MonotonicNs());
}

template <class Family>
void VehicleNodeOf<Family>::ControlTick(int64_t now_ns) {
  // The further cameras' aims before the tick, so the tick sends them.
  if (!rigs_.empty()) AimCameras();
  if (!core_.ControlTick(now_ns)) return;
  video::CameraPose pose = Family::CameraPoseOf(core_.adapter().State());
  pose.command_seq = core_.commands().applied().seq;
  camera_->SetPose(pose);
  if (!rigs_.empty()) ShowCameras();
  if (core_.state_due()) {
    PublishState(now_ns);
    if (camera_status_) PublishCameras(now_ns);
  }
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
  for (const auto& rig : rigs_) {
    c.camera_commands_accepted += rig->commands.accepted();
    c.camera_commands_malformed += rig->commands.malformed();
    c.camera_commands_refused += rig->commands.refused();
    c.camera_frames_published += rig->streamer->Counters().frames_published;
  }
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
