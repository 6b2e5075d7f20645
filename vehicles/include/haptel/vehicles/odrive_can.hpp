#pragma once
/// @file The ODrive "CAN Simple" protocol, firmware 0.5.x: 11-bit ids
/// `node << 5 | command`, little-endian payloads. Only what the robot uses.
/// Encoders build frames; decoders check id, length and values and say why
/// they refuse a frame (wrong length, non-finite float, unknown id).
#include <linux/can.h>

#include <cstdint>
#include <optional>
#include <string>

namespace haptel::vehicles::odrive {

enum Command : uint32_t {
  kHeartbeat = 0x001,
  kEstop = 0x002,
  kSetAxisState = 0x007,
  kEncoderEstimates = 0x009,
  kSetControllerMode = 0x00B,
  kSetInputVel = 0x00D,
  kClearErrors = 0x018,
};

enum AxisState : uint32_t {
  kUndefined = 0,
  kIdle = 1,
  kClosedLoop = 8,
};

constexpr uint32_t kControlModeVelocity = 2;
constexpr uint32_t kInputModeVelRamp = 2;

/// Axis error bits of firmware 0.5.x (Axis.Error).
enum AxisError : uint32_t {
  kErrorInvalidState = 0x1,
  kErrorMotorFailed = 0x40,
  kErrorSensorlessEstimatorFailed = 0x80,
  kErrorEncoderFailed = 0x100,
  kErrorControllerFailed = 0x200,
  kErrorWatchdogTimerExpired = 0x800,
  kErrorMinEndstopPressed = 0x1000,
  kErrorMaxEndstopPressed = 0x2000,
  kErrorEstopRequested = 0x4000,
  kErrorHomingWithoutEndstop = 0x20000,
  kErrorOverTemp = 0x40000,
  kErrorUnknownPosition = 0x80000,
};

constexpr uint32_t Id(int node, uint32_t command) {
  return (static_cast<uint32_t>(node) << 5) | command;
}
constexpr int NodeOf(uint32_t id) { return static_cast<int>((id >> 5) & 0x3F); }
constexpr uint32_t CommandOf(uint32_t id) { return id & 0x1F; }

can_frame Estop(int node);
can_frame SetAxisState(int node, uint32_t state);
can_frame SetControllerMode(int node, uint32_t control_mode, uint32_t input_mode);
can_frame SetInputVel(int node, float turns_per_s, float torque_ff = 0.0F);
can_frame ClearErrors(int node);
/// What a node sends: heartbeat (error, state, the error flags of 0.5.x:
/// motor, encoder, controller; bit 7 of the last, trajectory done) and the
/// encoder estimates (position turns, velocity turn/s).
can_frame Heartbeat(int node, uint32_t axis_error, uint32_t state, uint8_t motor_flag = 0,
                    uint8_t encoder_flag = 0, uint8_t controller_flag = 0);
can_frame EncoderEstimates(int node, float position_turns, float velocity_turns_per_s);

struct HeartbeatMsg {
  uint32_t axis_error = 0;
  uint32_t state = 0;
  uint8_t motor_flag = 0;
  uint8_t encoder_flag = 0;
  uint8_t controller_flag = 0;
};
struct EncoderMsg {
  float position_turns = 0.0F;
  float velocity_turns_per_s = 0.0F;
};
struct SetInputVelMsg {
  float turns_per_s = 0.0F;
  float torque_ff = 0.0F;
};
struct ControllerModeMsg {
  uint32_t control_mode = 0;
  uint32_t input_mode = 0;
};

/// Each: the message, or nullopt with `why` set ("length 3, expected 8",
/// "non-finite velocity"). The id's command must match (not checked here).
std::optional<HeartbeatMsg> DecodeHeartbeat(const can_frame& f, std::string* why = nullptr);
std::optional<EncoderMsg> DecodeEncoderEstimates(const can_frame& f, std::string* why = nullptr);
std::optional<SetInputVelMsg> DecodeSetInputVel(const can_frame& f, std::string* why = nullptr);
std::optional<ControllerModeMsg> DecodeControllerMode(const can_frame& f,
                                                      std::string* why = nullptr);
std::optional<uint32_t> DecodeAxisState(const can_frame& f, std::string* why = nullptr);

/// "MOTOR_FAILED | ENCODER_FAILED" (unknown bits as hex); "none" for 0.
std::string DescribeAxisError(uint32_t bits);
/// "IDLE", "CLOSED_LOOP_CONTROL", or the number.
std::string DescribeAxisState(uint32_t state);

}  // namespace haptel::vehicles::odrive

namespace haptel::vehicles::io_node {

/// The bumper I/O node's frames (vehicles/CAN.md), ids `node << 5 | command`
/// like the ODrives' so one node-id plan covers the bus.
enum Command : uint32_t {
  kHeartbeat = 0x001,  ///< 2 bytes: state (1 operational), error bits
  kInputs = 0x01E,     ///< 2 bytes: bit 0 left bumper, bit 1 right bumper; a counter
};
constexpr uint8_t kOperational = 1;

can_frame Heartbeat(int node, uint8_t state, uint8_t errors = 0);
can_frame Inputs(int node, bool bumper_left, bool bumper_right, uint8_t counter);

struct InputsMsg {
  bool bumper_left = false;
  bool bumper_right = false;
  uint8_t counter = 0;
};
struct HeartbeatMsg {
  uint8_t state = 0;
  uint8_t errors = 0;
};
std::optional<InputsMsg> DecodeInputs(const can_frame& f, std::string* why = nullptr);
std::optional<HeartbeatMsg> DecodeHeartbeat(const can_frame& f, std::string* why = nullptr);

}  // namespace haptel::vehicles::io_node
