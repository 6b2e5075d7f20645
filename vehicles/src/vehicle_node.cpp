#include "haptel/vehicles/vehicle_node.hpp"

#include <cmath>
#include <ctime>
#include <stdexcept>
#include <string>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/vehicles/can_robot.hpp"
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
  throw std::invalid_argument("vehicle kind '" + config.kind + "' has no adapter");
}

VehicleNode::VehicleNode(const VehicleConfig& config, const Track& track,
                         std::unique_ptr<video::CameraSource> camera, std::unique_ptr<VehicleAdapter> adapter)
    : config_(Validated(config)),
      adapter_(adapter != nullptr ? std::move(adapter) : MakeVehicleAdapter(config, track)),
      sequence_(config.watchdog_timeout_s),
      watchdog_(config.watchdog_timeout_s) {
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
  const int64_t now = MonotonicNs();
  if (!std::isfinite(cmd.left()) || !std::isfinite(cmd.right()) ||
      std::abs(cmd.left()) > kMaxCommand || std::abs(cmd.right()) > kMaxCommand) {
    malformed_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  if (!sequence_.Accept(cmd.seq(), now)) {
    stale_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  accepted_.fetch_add(1, std::memory_order_relaxed);
  command_.Store({cmd.seq(), cmd.sent_ns(), now, cmd.left(), cmd.right()});
}

void VehicleNode::ControlTick(int64_t now_ns) {
  const uint64_t version = command_.Version();
  if (version != applied_version_) {
    applied_version_ = version;
    applied_ = command_.Load();
    watchdog_.Feed(applied_.received_ns);
  }
  const bool expired = watchdog_.Check(now_ns);
  expired_.store(expired, std::memory_order_relaxed);
  trips_.store(watchdog_.trips(), std::memory_order_relaxed);
  if (expired) {
    adapter_->Stop();  // hardware: zero velocity, then idle
  } else {
    adapter_->SetMotors({QuantiseCommand(applied_.left, config_.drive.speed_levels),
                         QuantiseCommand(applied_.right, config_.drive.speed_levels)});
  }
  const double dt = last_tick_ns_ == 0 ? 1.0 / config_.sim_rate_hz
                                       : std::min(0.05, NsToS(now_ns - last_tick_ns_));
  last_tick_ns_ = now_ns;
  adapter_->Update(dt);
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
  m.watchdog_tripped(expired_.load());
  m.last_command_seq(applied_.seq);
  m.last_command_sent_ns(applied_.sent_ns);
  m.last_command_age_ns(applied_.seq == 0 ? 0 : now_ns - applied_.received_ns);
  m.commands_received(accepted_.load());
  m.fault(s.fault);
  m.fault_message(s.fault_message);
  state_writer_->Write(m);
  states_.fetch_add(1, std::memory_order_relaxed);
}

NodeCounters VehicleNode::Counters() const {
  NodeCounters c;
  c.commands_accepted = accepted_.load();
  c.commands_malformed = malformed_.load();
  c.commands_stale = stale_.load();
  c.watchdog_trips = trips_.load();
  c.states_published = states_.load();
  const CameraCounters camera = camera_->Counters();
  c.frames_published = camera.frames_published;
  c.frames_failed = camera.frames_failed;
  c.grabs_failed = camera.grabs_failed;
  c.camera_stalls = camera.camera_stalls;
  c.camera_ended = camera.camera_ended;
  c.watchdog_expired = expired_.load();
  return c;
}

}  // namespace haptel::vehicles
