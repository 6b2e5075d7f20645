#include "haptel/vehicles/vehicle_node.hpp"

#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/vehicles/can_robot.hpp"
#include "haptel/vehicles/ros2_robot.hpp"
#include "haptel/vehicles/sim_can_robot.hpp"
#include "haptel/vehicles/sim_robot.hpp"

namespace haptel::vehicles {

namespace {
/// "20261124T153012Z": a log file's time of creation, UTC.
std::string FileStamp(int64_t wall_ns) {
  const time_t seconds = static_cast<time_t>(wall_ns / 1'000'000'000);
  tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y%m%dT%H%M%SZ", &utc);
  return text;
}

/// Commands a little past ±1 are rounding; anything further is malformed.
constexpr float kMaxCommand = 1.001F;
}  // namespace

std::unique_ptr<VehicleAdapter> MakeVehicleAdapter(const VehicleConfig& config, const Track& track) {
  if (config.kind == "sim-robot") return std::make_unique<SimRobot>(track, config);
  std::unique_ptr<CandumpWriter> log;
  auto open_log = [&] {
    if (config.can.log_dir.empty()) return;
    const std::string stamp = FileStamp(WallNs());
    log = std::make_unique<CandumpWriter>(config.can.log_dir / (config.name + "-" + stamp + ".log"),
                                          config.can.interface);
  };
  if (config.kind == "can-robot") {
    auto bus = std::make_unique<SocketCanBus>(config.can.interface);  // CanUnavailable: set-up error
    open_log();
    return std::make_unique<CanRobot>(std::move(bus), config, std::move(log));
  }
  if (config.kind == "can-robot-sim") {
    open_log();
    return std::make_unique<SimulatedCanRobot>(track, config, std::move(log));
  }
  if (config.kind == "ros2") return std::make_unique<Ros2Robot>(config, track);
  throw std::invalid_argument("vehicle kind '" + config.kind + "' has no adapter");
}

VehicleNode::VehicleNode(const VehicleConfig& config, const Track& track,
                         std::unique_ptr<video::CameraSource> camera, std::unique_ptr<VehicleAdapter> adapter)
    : config_(Validated(config)),
      adapter_(adapter != nullptr ? std::move(adapter) : MakeVehicleAdapter(config, track)),
      commands_(config.watchdog_timeout_s) {
  if (camera == nullptr) throw std::invalid_argument("VehicleNode: no camera source");
  ticks_per_state_ = std::max(1, static_cast<int>(std::lround(config.sim_rate_hz / config.state_rate_hz)));

  participant_ = std::make_unique<link::Participant>(config.link, "haptel-vehicle-" + config.name);
  state_writer_ = std::make_unique<link::StateWriter>(
      *participant_, link::TopicName(config.name, "state"), link::Profile::kState);
  camera_ = std::make_unique<CameraStreamer>(config.camera, std::move(camera), *participant_, config.name);
  const AdapterState s = adapter_->State();
  camera_->SetPose({.x = s.x, .y = s.y, .heading = s.heading});
  command_reader_ = std::make_unique<link::CommandReader>(
      *participant_, link::TopicName(config.name, "command"), link::Profile::kCommand,
      [this](const msg::DriveCommand& cmd) { OnCommand(cmd); });

  control_ = std::make_unique<PeriodicThread>(
      PeriodicThread::Options{.name = "vehicle-control", .rate_hz = config.sim_rate_hz},
      [this](int64_t now) { ControlTick(now); });
}

VehicleNode::~VehicleNode() { Stop(); }

void VehicleNode::Start() {
  control_->Start();
  camera_->Start();
}

void VehicleNode::Stop() {
  if (stopped_.exchange(true)) return;
  camera_->Stop();
  control_->Stop();
  adapter_->Stop();
  adapter_->Update(1e-3);
  PublishState(MonotonicNs());
}

void VehicleNode::OnCommand(const msg::DriveCommand& cmd) {
  const bool valid = std::isfinite(cmd.left()) && std::isfinite(cmd.right()) &&
                     std::abs(cmd.left()) <= kMaxCommand && std::abs(cmd.right()) <= kMaxCommand;
  commands_.Offer(valid, {cmd.session(), cmd.operator_name().c_str(), cmd.release()}, cmd.seq(), cmd.sent_ns(),
                  {cmd.left(), cmd.right()}, MonotonicNs());
}

void VehicleNode::ControlTick(int64_t now_ns) {
  if (commands_.Poll(now_ns)) {
    adapter_->Stop();  // hardware: zero velocity, then idle
  } else {
    const Wheels& w = commands_.applied().command;
    adapter_->SetMotors({QuantiseCommand(w.left, config_.drive.speed_levels),
                         QuantiseCommand(w.right, config_.drive.speed_levels)});
  }
  adapter_->Update(ControlStep(last_tick_ns_, now_ns, config_.sim_rate_hz));
  const AdapterState s = adapter_->State();
  camera_->SetPose({.x = s.x, .y = s.y, .heading = s.heading});
  if (tick_count_++ % static_cast<uint64_t>(ticks_per_state_) == 0) PublishState(now_ns);
}

void VehicleNode::PublishState(int64_t now_ns) {
  const AdapterState s = adapter_->State();
  msg::VehicleState& m = state_msg_;
  m.seq(++state_seq_);
  m.stamp_ns(now_ns);
  m.speed(static_cast<float>(s.speed));
  m.yaw_rate(static_cast<float>(s.yaw_rate));
  m.pose_valid(s.pose_valid);
  m.x(static_cast<float>(s.x));
  m.y(static_cast<float>(s.y));
  m.heading(static_cast<float>(s.heading));
  m.bumper_left(s.bumper_left);
  m.bumper_right(s.bumper_right);
  m.motor_left_level(static_cast<int16_t>(s.applied.left));
  m.motor_right_level(static_cast<int16_t>(s.applied.right));
  m.watchdog_tripped(commands_.watchdog_expired());
  m.last_command_seq(commands_.applied().seq);
  m.last_command_sent_ns(commands_.applied().sent_ns);
  m.last_command_age_ns(commands_.AppliedAgeNs(now_ns));
  m.commands_received(commands_.accepted());
  const CommandOwnerInfo owner = commands_.owner();
  m.owner_session(owner.session);
  m.owner(owner.name);
  m.commands_refused(commands_.refused());
  m.fault(s.fault);
  m.fault_message(s.fault_message);
  state_writer_->Write(m);
  states_.fetch_add(1, std::memory_order_relaxed);
}

NodeCounters VehicleNode::Counters() const {
  return MakeNodeCounters(commands_, camera_->Counters(), states_.load());
}

}  // namespace haptel::vehicles
