#include "haptel/vehicles/can_robot.hpp"

#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/link/topic.hpp"
#include "haptel/vehicles/odrive_can.hpp"

namespace haptel::vehicles {
namespace {

constexpr int kLeft = 0;
constexpr int kRight = 1;
constexpr int kIo = 2;
const char* const kNodeNames[] = {"left wheel", "right wheel", "bumper I/O node"};

const CanConfig& ValidatedCan(const VehicleConfig& config) {
  try {
    config.can.ValidateOrThrow(config.drive.speed_levels);
  } catch (const ConfigFieldError& e) {
    throw e.Within("can");
  }
  return config.can;
}

}  // namespace

CanRobot::CanRobot(std::unique_ptr<CanBus> bus, const VehicleConfig& config,
                   std::unique_ptr<CandumpWriter> log)
    : bus_(std::move(bus)),
      can_(ValidatedCan(config)),
      track_width_(config.drive.track_width),
      log_(std::move(log)) {
  if (bus_ == nullptr) throw std::invalid_argument("CanRobot: no bus");
  state_.pose_valid = false;  // a real robot knows no pose; a tracker would give it
  if (log_) log_status_.path = std::filesystem::absolute(log_->path()).string();
}

void CanRobot::UpdateLogStatus() {
  if (!log_) return;
  CanLogStatus& s = log_status_;
  s.frames = log_->frames_written();
  s.frames_lost = log_->frames_lost();
  if (s.error.empty() && !log_->error().empty()) s.error = log_->error();
}

double CanRobot::LevelTurns(int level) const {
  if (level == 0) return 0.0;
  const size_t index = static_cast<size_t>(
      std::min(std::abs(level), static_cast<int>(can_.level_turns_per_s.size())));
  return (level > 0 ? 1.0 : -1.0) * can_.level_turns_per_s[index - 1];
}

void CanRobot::Send(const can_frame& frame) {
  if (bus_lost_) return;
  bool sent = false;
  try {
    sent = bus_->Send(frame);
  } catch (const CanBusLost& e) {
    bus_lost_ = true;
    Fault(e.what());
    return;
  }
  if (sent) {
    ++counters_.sent;
    if (log_) log_->Write(frame, WallNs());
  } else {
    ++counters_.send_failed;
  }
}

void CanRobot::StartAxes() {
  for (const int node : {can_.left_node, can_.right_node}) {
    Send(odrive::SetControllerMode(node, odrive::kControlModeVelocity, odrive::kInputModeVelRamp));
    Send(odrive::SetAxisState(node, odrive::kClosedLoop));
  }
  started_ = true;
  idle_ = false;
}

void CanRobot::SetMotors(const models::MotorLevels& levels) {
  if (state_.fault) return;  // stopped until ClearErrors
  if (idle_ && (levels.left != 0 || levels.right != 0)) StartAxes();
  if (idle_) return;
  wheel_cmd_[kLeft] = LevelTurns(levels.left);
  wheel_cmd_[kRight] = (can_.right_reversed ? -1.0 : 1.0) * LevelTurns(levels.right);
  state_.applied = levels;
}

void CanRobot::Stop() {
  wheel_cmd_ = {0.0, 0.0};
  state_.applied = {};
  if (idle_ || !started_) return;
  for (const int node : {can_.left_node, can_.right_node}) Send(odrive::SetInputVel(node, 0.0F));
  for (const int node : {can_.left_node, can_.right_node})
    Send(odrive::SetAxisState(node, odrive::kIdle));
  idle_ = true;
}

void CanRobot::Fault(const std::string& message) {
  if (state_.fault) return;
  state_.fault = true;
  state_.fault_message = message;
  ++counters_.faults;
  wheel_cmd_ = {0.0, 0.0};
  state_.applied = {};
  for (const int node : {can_.left_node, can_.right_node}) Send(odrive::SetInputVel(node, 0.0F));
  for (const int node : {can_.left_node, can_.right_node})
    Send(odrive::SetAxisState(node, odrive::kIdle));
  idle_ = true;
}

void CanRobot::ClearErrors() {
  for (const int node : {can_.left_node, can_.right_node}) Send(odrive::ClearErrors(node));
  state_.fault = false;
  state_.fault_message.clear();
  // The nodes get a fresh start before their silence counts again.
  for (double& t : last_heartbeat_s_) t = t_s_;
  StartAxes();
}

void CanRobot::Decode(const can_frame& frame) {
  ++counters_.received;
  if ((frame.can_id & CAN_ERR_FLAG) != 0) {
    ++counters_.error_frames;
    const uint32_t cls = frame.can_id & CAN_ERR_MASK;
    if ((cls & CAN_ERR_CRTL) != 0 &&
        (frame.data[1] & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) != 0) {
      ++counters_.error_passive;
    }
    if ((cls & CAN_ERR_RESTARTED) != 0) ++counters_.restarted;
    if ((cls & CAN_ERR_BUSOFF) != 0) {
      ++counters_.bus_off;
      Fault("CAN bus " + bus_->name() + " is bus-off: the controller stopped sending");
    }
    return;
  }
  if ((frame.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) != 0 || frame.can_dlc > CAN_MAX_DLEN) {
    ++counters_.unknown;
    return;
  }
  const int node = odrive::NodeOf(frame.can_id);
  const uint32_t command = odrive::CommandOf(frame.can_id);
  const int wheel = node == can_.left_node ? kLeft : node == can_.right_node ? kRight : -1;
  if (wheel >= 0 && command == odrive::kHeartbeat) {
    const auto m = odrive::DecodeHeartbeat(frame);
    if (!m) {
      ++counters_.malformed;
      return;
    }
    ++counters_.heartbeats;
    last_heartbeat_s_[static_cast<size_t>(wheel)] = t_s_;
    axis_state_[static_cast<size_t>(wheel)] = m->state;
    if (m->axis_error != 0) {
      Fault(std::string(kNodeNames[wheel]) + " (ODrive node " + std::to_string(node) +
            ") reports axis error " + odrive::DescribeAxisError(m->axis_error) + "; robot stopped");
    }
    return;
  }
  if (wheel >= 0 && command == odrive::kEncoderEstimates) {
    const auto m = odrive::DecodeEncoderEstimates(frame);
    if (!m) {
      ++counters_.malformed;
      return;
    }
    wheel_vel_[static_cast<size_t>(wheel)] = m->velocity_turns_per_s;
    const double left = wheel_vel_[kLeft] * can_.wheel_circumference;
    const double right =
        (can_.right_reversed ? -1.0 : 1.0) * wheel_vel_[kRight] * can_.wheel_circumference;
    state_.speed = 0.5 * (left + right);
    state_.yaw_rate = (right - left) / track_width_;
    return;
  }
  if (node == can_.io_node && command == io_node::kHeartbeat) {
    if (!io_node::DecodeHeartbeat(frame)) {
      ++counters_.malformed;
      return;
    }
    ++counters_.heartbeats;
    last_heartbeat_s_[kIo] = t_s_;
    return;
  }
  if (node == can_.io_node && command == io_node::kInputs) {
    const auto m = io_node::DecodeInputs(frame);
    if (!m) {
      ++counters_.malformed;
      return;
    }
    state_.bumper_left = m->bumper_left;
    state_.bumper_right = m->bumper_right;
    return;
  }
  ++counters_.unknown;
}

void CanRobot::Update(double dt) {
  if (dt > 0.0 && std::isfinite(dt)) t_s_ += dt;
  if (!started_) {
    for (double& t : last_heartbeat_s_) t = t_s_;  // silence counts from the start
    StartAxes();
  }
  can_frame frame{};
  try {
    while (!bus_lost_ && bus_->Receive(frame)) {
      if (log_) log_->Write(frame, WallNs());
      Decode(frame);
    }
  } catch (const CanBusLost& e) {
    bus_lost_ = true;
    Fault(e.what());
  }
  const double limit = 3.0 * can_.heartbeat_period_s;
  for (int i = 0; i < 3 && !state_.fault; ++i) {
    const double silent = t_s_ - last_heartbeat_s_[static_cast<size_t>(i)];
    if (silent > limit) {
      const int node = i == kLeft ? can_.left_node : i == kRight ? can_.right_node : can_.io_node;
      char seconds[16];
      std::snprintf(seconds, sizeof seconds, "%.2f", silent);
      Fault(std::string(kNodeNames[i]) + " (node " + std::to_string(node) +
            ") silent: no heartbeat for " + seconds + " s; robot stopped");
    }
  }
  if (t_s_ + 1e-9 >= next_command_s_) {
    next_command_s_ = std::max(next_command_s_ + 1.0 / can_.command_rate_hz, t_s_);
    if (!idle_) {
      Send(odrive::SetInputVel(can_.left_node, static_cast<float>(wheel_cmd_[kLeft])));
      Send(odrive::SetInputVel(can_.right_node, static_cast<float>(wheel_cmd_[kRight])));
    }
  }
  UpdateLogStatus();
}

namespace {

class CanLogReport final : public KindReport {
 public:
  explicit CanLogReport(const CanRobot& robot) : robot_(robot) {}

  void Open(link::Participant& participant, const std::string& vehicle) override {
    writer_ = std::make_unique<link::CanLogWriter>(participant, link::TopicName(vehicle, "can_log"),
                                                   link::Profile::kLatched);
  }

  void Publish() override {
    const CanLogStatus& now = robot_.log_status();
    if (writer_ == nullptr || now.path.empty() || (published_ && now == last_)) return;
    last_ = now;
    message_.path(now.path);
    message_.frames(now.frames);
    message_.frames_lost(now.frames_lost);
    message_.error(now.error);
    published_ = writer_->Write(message_);
  }

 private:
  const CanRobot& robot_;
  std::unique_ptr<link::CanLogWriter> writer_;
  msg::CanLogStatus message_;
  CanLogStatus last_;
  bool published_ = false;
};

}  // namespace

std::unique_ptr<KindReport> MakeCanLogReport(const CanRobot& robot) {
  return std::make_unique<CanLogReport>(robot);
}

}  // namespace haptel::vehicles
