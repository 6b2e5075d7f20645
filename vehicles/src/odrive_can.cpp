#include "haptel/vehicles/odrive_can.hpp"

#include <cmath>
#include <cstring>

#include "haptel/vehicles/can_bus.hpp"

namespace haptel::vehicles {
namespace {

void PutU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void PutF32(uint8_t* p, float v) {
  uint32_t bits = 0;
  std::memcpy(&bits, &v, 4);
  PutU32(p, bits);
}
uint32_t GetU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
         static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}
float GetF32(const uint8_t* p) {
  const uint32_t bits = GetU32(p);
  float v = 0.0F;
  std::memcpy(&v, &bits, 4);
  return v;
}

/// Refuses frames that are not plain data frames of `len` bytes.
bool Shape(const can_frame& f, uint8_t len, std::string* why) {
  if ((f.can_id & (CAN_ERR_FLAG | CAN_RTR_FLAG | CAN_EFF_FLAG)) != 0) {
    if (why) *why = "not a standard data frame";
    return false;
  }
  if (f.can_dlc != len) {
    if (why) *why = "length " + std::to_string(f.can_dlc) + ", expected " + std::to_string(len);
    return false;
  }
  return true;
}

bool Finite(float v, const char* what, std::string* why) {
  if (std::isfinite(v)) return true;
  if (why) *why = std::string("non-finite ") + what;
  return false;
}

}  // namespace

namespace odrive {

can_frame Estop(int node) { return MakeFrame(Id(node, kEstop), nullptr, 0); }
can_frame ClearErrors(int node) { return MakeFrame(Id(node, kClearErrors), nullptr, 0); }

can_frame SetAxisState(int node, uint32_t state) {
  uint8_t d[4];
  PutU32(d, state);
  return MakeFrame(Id(node, kSetAxisState), d, 4);
}

can_frame SetControllerMode(int node, uint32_t control_mode, uint32_t input_mode) {
  uint8_t d[8];
  PutU32(d, control_mode);
  PutU32(d + 4, input_mode);
  return MakeFrame(Id(node, kSetControllerMode), d, 8);
}

can_frame SetInputVel(int node, float turns_per_s, float torque_ff) {
  uint8_t d[8];
  PutF32(d, turns_per_s);
  PutF32(d + 4, torque_ff);
  return MakeFrame(Id(node, kSetInputVel), d, 8);
}

can_frame Heartbeat(int node, uint32_t axis_error, uint32_t state, uint8_t motor_flag,
                    uint8_t encoder_flag, uint8_t controller_flag) {
  uint8_t d[8];
  PutU32(d, axis_error);
  d[4] = static_cast<uint8_t>(state);
  d[5] = motor_flag;
  d[6] = encoder_flag;
  d[7] = controller_flag;
  return MakeFrame(Id(node, kHeartbeat), d, 8);
}

can_frame EncoderEstimates(int node, float position_turns, float velocity_turns_per_s) {
  uint8_t d[8];
  PutF32(d, position_turns);
  PutF32(d + 4, velocity_turns_per_s);
  return MakeFrame(Id(node, kEncoderEstimates), d, 8);
}

std::optional<HeartbeatMsg> DecodeHeartbeat(const can_frame& f, std::string* why) {
  if (!Shape(f, 8, why)) return std::nullopt;
  HeartbeatMsg m;
  m.axis_error = GetU32(f.data);
  m.state = f.data[4];
  m.motor_flag = f.data[5];
  m.encoder_flag = f.data[6];
  m.controller_flag = f.data[7];
  return m;
}

std::optional<EncoderMsg> DecodeEncoderEstimates(const can_frame& f, std::string* why) {
  if (!Shape(f, 8, why)) return std::nullopt;
  EncoderMsg m{GetF32(f.data), GetF32(f.data + 4)};
  if (!Finite(m.position_turns, "position", why) ||
      !Finite(m.velocity_turns_per_s, "velocity", why)) {
    return std::nullopt;
  }
  return m;
}

std::optional<SetInputVelMsg> DecodeSetInputVel(const can_frame& f, std::string* why) {
  if (!Shape(f, 8, why)) return std::nullopt;
  SetInputVelMsg m{GetF32(f.data), GetF32(f.data + 4)};
  if (!Finite(m.turns_per_s, "velocity", why) || !Finite(m.torque_ff, "torque feed-forward", why)) {
    return std::nullopt;
  }
  return m;
}

std::optional<ControllerModeMsg> DecodeControllerMode(const can_frame& f, std::string* why) {
  if (!Shape(f, 8, why)) return std::nullopt;
  return ControllerModeMsg{GetU32(f.data), GetU32(f.data + 4)};
}

std::optional<uint32_t> DecodeAxisState(const can_frame& f, std::string* why) {
  if (!Shape(f, 4, why)) return std::nullopt;
  return GetU32(f.data);
}

std::string DescribeAxisError(uint32_t bits) {
  if (bits == 0) return "none";
  static const std::pair<uint32_t, const char*> kNames[] = {
      {kErrorInvalidState, "INVALID_STATE"},
      {kErrorMotorFailed, "MOTOR_FAILED"},
      {kErrorSensorlessEstimatorFailed, "SENSORLESS_ESTIMATOR_FAILED"},
      {kErrorEncoderFailed, "ENCODER_FAILED"},
      {kErrorControllerFailed, "CONTROLLER_FAILED"},
      {kErrorWatchdogTimerExpired, "WATCHDOG_TIMER_EXPIRED"},
      {kErrorMinEndstopPressed, "MIN_ENDSTOP_PRESSED"},
      {kErrorMaxEndstopPressed, "MAX_ENDSTOP_PRESSED"},
      {kErrorEstopRequested, "ESTOP_REQUESTED"},
      {kErrorHomingWithoutEndstop, "HOMING_WITHOUT_ENDSTOP"},
      {kErrorOverTemp, "OVER_TEMP"},
      {kErrorUnknownPosition, "UNKNOWN_POSITION"},
  };
  std::string out;
  uint32_t rest = bits;
  for (const auto& [bit, name] : kNames) {
    if ((bits & bit) == 0) continue;
    out += (out.empty() ? "" : " | ") + std::string(name);
    rest &= ~bit;
  }
  if (rest != 0) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%X", rest);
    out += (out.empty() ? "" : " | ") + std::string(hex);
  }
  return out;
}

std::string DescribeAxisState(uint32_t state) {
  switch (state) {
    case kUndefined:
      return "UNDEFINED";
    case kIdle:
      return "IDLE";
    case kClosedLoop:
      return "CLOSED_LOOP_CONTROL";
    default:
      return std::to_string(state);
  }
}

}  // namespace odrive

namespace io_node {

can_frame Heartbeat(int node, uint8_t state, uint8_t errors) {
  const uint8_t d[2] = {state, errors};
  return MakeFrame(odrive::Id(node, kHeartbeat), d, 2);
}

can_frame Inputs(int node, bool bumper_left, bool bumper_right, uint8_t counter) {
  const uint8_t d[2] = {static_cast<uint8_t>((bumper_left ? 1 : 0) | (bumper_right ? 2 : 0)),
                        counter};
  return MakeFrame(odrive::Id(node, kInputs), d, 2);
}

std::optional<InputsMsg> DecodeInputs(const can_frame& f, std::string* why) {
  if (!Shape(f, 2, why)) return std::nullopt;
  if ((f.data[0] & ~0x03) != 0) {
    if (why) *why = "unknown input bits";
    return std::nullopt;
  }
  return InputsMsg{(f.data[0] & 1) != 0, (f.data[0] & 2) != 0, f.data[1]};
}

std::optional<HeartbeatMsg> DecodeHeartbeat(const can_frame& f, std::string* why) {
  if (!Shape(f, 2, why)) return std::nullopt;
  return HeartbeatMsg{f.data[0], f.data[1]};
}

}  // namespace io_node
}  // namespace haptel::vehicles
