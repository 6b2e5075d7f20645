#include "haptel/vehicles/sim_can_robot.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/vehicles/odrive_can.hpp"

namespace haptel::vehicles {
namespace {
constexpr double kEncoderPeriodS = 0.010;  // ODrive's encoder_rate_ms default
constexpr double kInputsPeriodS = 0.020;
}  // namespace

SimCanNodes::SimCanNodes(std::unique_ptr<CanBus> bus, const VehicleConfig& config, SimRobot& robot)
    : bus_(std::move(bus)), can_(config.can), drive_(config.drive), robot_(robot) {
  axes_[0].node = can_.left_node;
  axes_[1].node = can_.right_node;
}

void SimCanNodes::InjectAxisError(int wheel, uint32_t bits) {
  Axis& a = axes_[static_cast<size_t>(wheel)];
  a.error |= bits;
  a.state = odrive::kIdle;
}

void SimCanNodes::Silence(int node, bool silent) { silent_[static_cast<size_t>(node)] = silent; }

void SimCanNodes::SendErrorFrame(uint32_t error_class, const std::array<uint8_t, 8>& data) {
  can_frame f{};
  f.can_id = CAN_ERR_FLAG | (error_class & CAN_ERR_MASK);
  f.can_dlc = CAN_ERR_DLC;
  std::copy(data.begin(), data.end(), f.data);
  bus_->Send(f);
}

void SimCanNodes::Handle(const can_frame& f) {
  ++frames_in_;
  if ((f.can_id & (CAN_ERR_FLAG | CAN_EFF_FLAG | CAN_RTR_FLAG)) != 0) return;
  const int node = odrive::NodeOf(f.can_id);
  const uint32_t command = odrive::CommandOf(f.can_id);
  Axis* axis = nullptr;
  for (Axis& a : axes_) {
    if (a.node == node) axis = &a;
  }
  if (axis == nullptr || silent_[axis == &axes_[0] ? 0 : 1]) return;  // not ours, or a dead node
  switch (command) {
    case odrive::kSetAxisState: {
      const auto state = odrive::DecodeAxisState(f);
      if (!state) break;
      if (*state == odrive::kClosedLoop) {
        if (axis->error != 0) {
          axis->error |= odrive::kErrorInvalidState;  // as the firmware: refused while in error
        } else {
          axis->state = odrive::kClosedLoop;
        }
      } else if (*state == odrive::kIdle) {
        axis->state = odrive::kIdle;
      }
      return;
    }
    case odrive::kSetControllerMode: {
      if (const auto m = odrive::DecodeControllerMode(f)) {
        axis->control_mode = m->control_mode;
        axis->input_mode = m->input_mode;
        return;
      }
      break;
    }
    case odrive::kSetInputVel: {
      if (const auto m = odrive::DecodeSetInputVel(f)) {
        axis->input_vel = m->turns_per_s;
        return;
      }
      break;
    }
    case odrive::kEstop:
      axis->error |= odrive::kErrorEstopRequested;
      axis->state = odrive::kIdle;
      return;
    case odrive::kClearErrors:
      axis->error = 0;
      return;
    default:
      break;
  }
  ++frames_refused_;
}

void SimCanNodes::Step(double dt) {
  can_frame f{};
  while (bus_->Receive(f)) Handle(f);
  if (!(dt > 0.0)) return;
  t_s_ += dt;
  // The velocity ramp: closed loop in velocity mode follows input_vel at
  // vel_ramp_rate; idle lets the wheel stop (modelled as a ramp to zero).
  for (Axis& a : axes_) {
    const bool driving =
        a.state == odrive::kClosedLoop && a.control_mode == odrive::kControlModeVelocity;
    const float target = driving ? a.input_vel : 0.0F;
    const float step = static_cast<float>(can_.vel_ramp_rate * dt);
    a.vel += std::clamp(target - a.vel, -step, step);
    a.pos += a.vel * dt;
  }
  const double right_sign = can_.right_reversed ? -1.0 : 1.0;
  robot_.SetTreadTargets(axes_[0].vel * can_.wheel_circumference,
                         right_sign * axes_[1].vel * can_.wheel_circumference);
  robot_.Update(dt);

  if (t_s_ + 1e-9 >= next_heartbeat_s_) {
    next_heartbeat_s_ += can_.heartbeat_period_s;
    for (size_t i = 0; i < 2; ++i) {
      if (!silent_[i]) bus_->Send(odrive::Heartbeat(axes_[i].node, axes_[i].error, axes_[i].state));
    }
    if (!silent_[2]) bus_->Send(io_node::Heartbeat(can_.io_node, io_node::kOperational));
  }
  if (t_s_ + 1e-9 >= next_encoder_s_) {
    next_encoder_s_ += kEncoderPeriodS;
    for (size_t i = 0; i < 2; ++i) {
      if (!silent_[i]) {
        bus_->Send(odrive::EncoderEstimates(axes_[i].node, static_cast<float>(axes_[i].pos),
                                            axes_[i].vel));
      }
    }
  }
  const AdapterState s = robot_.State();
  const bool changed = s.bumper_left != last_left_ || s.bumper_right != last_right_;
  if (!silent_[2] && (changed || t_s_ + 1e-9 >= next_inputs_s_)) {
    if (t_s_ + 1e-9 >= next_inputs_s_) next_inputs_s_ += kInputsPeriodS;
    last_left_ = s.bumper_left;
    last_right_ = s.bumper_right;
    bus_->Send(io_node::Inputs(can_.io_node, s.bumper_left, s.bumper_right, ++inputs_counter_));
  }
}

SimulatedCanRobot::SimulatedCanRobot(const Track& track, const VehicleConfig& config,
                                     std::unique_ptr<CandumpWriter> log)
    : robot_(track, config) {
  auto [near, far] = MakeSocketPairBus();
  adapter_ = std::make_unique<CanRobot>(std::move(near), config, std::move(log));
  nodes_ = std::make_unique<SimCanNodes>(std::move(far), config, robot_);
}

void SimulatedCanRobot::Update(double dt) {
  if (!(dt > 0.0)) return;
  // A late control tick's time in pieces of at most half a heartbeat
  // period: in one piece the adapter would count the whole stall as the
  // nodes' silence before they had sent a frame of it, and stop the robot
  // (a real bus queues the nodes' frames while the host stalls).
  const double piece_s = 0.5 * nodes_->heartbeat_period_s();
  const int pieces = std::max(1, static_cast<int>(std::ceil(dt / piece_s - 1e-9)));
  for (int i = 0; i < pieces; ++i) {
    adapter_->Update(dt / pieces);
    nodes_->Step(dt / pieces);
  }
}

AdapterState SimulatedCanRobot::State() const {
  AdapterState s = adapter_->State();
  const AdapterState world = robot_.State();
  s.pose_valid = true;
  s.x = world.x;
  s.y = world.y;
  s.heading = world.heading;
  return s;
}

}  // namespace haptel::vehicles
