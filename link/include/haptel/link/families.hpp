#pragma once
/// @file What each vehicle family's link carries, shared by both ends: the
/// command and state messages, their writers and readers, and how a command
/// goes into its message and comes out of it (with the vehicle's range
/// check). The vehicle node (vehicles/families.hpp) and the operator's link
/// (mediator/vehicle_link.hpp) are written once over these.
#include <cmath>
#include <cstdint>
#include <string>

#include "haptel/config/vehicle_kinds.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/core/camera_aim.hpp"
#include "haptel/core/tread_command.hpp"
#include "haptel/link/topic.hpp"

namespace haptel::link {

/// Where a vehicle is and how it moves, whatever its family: what a person
/// beside the driver (a camera station) reads of its state. SI units.
struct VehicleGlance {
  bool pose_valid = false;  ///< the vehicle knows its pose (simulators do)
  double x = 0.0, y = 0.0;  ///< m, the track's or course's frame
  bool flies = false;       ///< z is an altitude (the blimp)
  double z = 0.0;           ///< m, up
  double heading = 0.0;     ///< rad, counter-clockwise from +x
  double speed = 0.0;       ///< m/s over the ground
  bool failsafe = false;    ///< its watchdog holds it (no fresh driving command)
  uint64_t seq = 0;         ///< the state's seq (0: none yet)
};

/// The robot: each tread's command (TreadCommand), the ground state (VehicleState).
struct RobotMessages {
  static constexpr VehicleFamily kFamily = VehicleFamily::kRobot;
  using Command = TreadCommand;
  using CommandMsg = msg::TreadCommand;
  using StateMsg = msg::VehicleState;
  using CommandType = msg::TreadCommandPubSubType;
  using StateType = msg::VehicleStatePubSubType;
  using CommandWriter = link::TreadCommandWriter;
  using CommandReader = link::TreadCommandReader;
  using StateWriter = link::StateWriter;
  using StateReader = link::StateReader;

  /// Commands a little past ±1 are a float's rounding; anything further is malformed.
  static constexpr float kMaxCommand = 1.001F;
  /// The values of `c` into `m` (the caller stamps sequence and time).
  static void Encode(const Command& c, CommandMsg& m) {
    m.left(static_cast<float>(c.left));
    m.right(static_cast<float>(c.right));
  }
  /// The command in `m`; false when it is malformed (non-finite, out of range).
  static bool Decode(const CommandMsg& m, Command& out) {
    out = {m.left(), m.right()};
    return std::isfinite(m.left()) && std::isfinite(m.right()) &&
           std::abs(m.left()) <= kMaxCommand && std::abs(m.right()) <= kMaxCommand;
  }
  /// The vehicle's command watchdog holds it stopped.
  static bool WatchdogTripped(const StateMsg& s) { return s.watchdog_tripped(); }
  static VehicleGlance Glance(const StateMsg& s) {
    VehicleGlance g;
    g.pose_valid = s.pose_valid();
    g.x = s.x();
    g.y = s.y();
    g.heading = s.heading();
    g.speed = std::abs(s.speed());
    g.failsafe = s.watchdog_tripped();
    g.seq = s.seq();
    return g;
  }
};

/// The blimp: seven channels (BlimpCommand), the flight state (BlimpState).
struct BlimpMessages {
  static constexpr VehicleFamily kFamily = VehicleFamily::kBlimp;
  using Command = BlimpCommand;
  using CommandMsg = msg::BlimpCommand;
  using StateMsg = msg::BlimpState;
  using CommandType = msg::BlimpCommandPubSubType;
  using StateType = msg::BlimpStatePubSubType;
  using CommandWriter = link::BlimpCommandWriter;
  using CommandReader = link::BlimpCommandReader;
  using StateWriter = link::BlimpStateWriter;
  using StateReader = link::BlimpStateReader;

  /// A float's rounding past a range's end is not malformed.
  static constexpr double kRangeSlack = 1e-3;
  static void Encode(const Command& c, CommandMsg& m) {
    m.elevator(static_cast<float>(c.elevator));
    m.rudder(static_cast<float>(c.rudder));
    m.power(static_cast<float>(c.power));
    m.helix(static_cast<float>(c.helix));
    m.tail_rotor(static_cast<float>(c.tail_rotor));
    m.camera_pan(static_cast<float>(c.camera_pan));
    m.camera_tilt(static_cast<float>(c.camera_tilt));
  }
  /// The command in `m`, clamped into range; false when it was malformed.
  static bool Decode(const CommandMsg& m, Command& out) {
    const BlimpCommand c{m.elevator(),   m.rudder(),     m.power(),      m.helix(),
                         m.tail_rotor(), m.camera_pan(), m.camera_tilt()};
    out = Clamped(c);
    return InRange(c, kRangeSlack);
  }
  /// The vehicle's command watchdog holds every channel at neutral.
  static bool WatchdogTripped(const StateMsg& s) { return s.failsafe(); }
  static VehicleGlance Glance(const StateMsg& s) {
    VehicleGlance g;
    g.pose_valid = s.pose_valid();
    g.x = s.x();
    g.y = s.y();
    g.flies = true;
    g.z = s.z();
    g.heading = s.yaw();
    g.speed = std::hypot(s.vx(), s.vy(), s.vz());
    g.failsafe = s.failsafe();
    g.seq = s.seq();
    return g;
  }
};

/// Calls `f.template operator()<Messages>()` with the family's messages
/// (RobotMessages, BlimpMessages): code written once over every family,
/// for a family known only at run time (a station learns it from the
/// vehicle's CameraStatus). Returns what `f` returns.
template <class F>
decltype(auto) ForFamily(VehicleFamily family, F&& f) {
  switch (family) {
    case VehicleFamily::kBlimp:
      return f.template operator()<BlimpMessages>();
    case VehicleFamily::kRobot:
      break;
  }
  return f.template operator()<RobotMessages>();
}

/// A vehicle's cameras (issue 38): each camera's video is its own stream
/// with its own feedback; a steerable camera takes CameraCommands on a topic
/// of its own, apart from the driving topics, so DDS Security can grant it
/// alone (the camera station's identity); CameraStatus says what cameras
/// there are and where each points. Names: a camera's name is a topic's
/// path segment (config: [a-z0-9_-], at most 31 characters).
///
///   haptel/<vehicle>/video                   the driven camera's VideoFrame (as ever)
///   haptel/<vehicle>/video_feedback          its VideoFeedback (as ever)
///   haptel/<vehicle>/video/<camera>          every other camera's VideoFrame (kVideo)
///   haptel/<vehicle>/video_feedback/<camera> its VideoFeedback (kState)
///   haptel/<vehicle>/camera/<camera>         CameraCommand, station → vehicle (kCommand)
///   haptel/<vehicle>/cameras                 CameraStatus, vehicle → anyone (kLatched)
///
/// The driven camera is the vehicle file's first: the driver's, steered by
/// the driving command (the blimp's camera_pan/tilt), never by a CameraCommand.
inline std::string VideoTopic(const std::string& vehicle, const std::string& camera, bool driven) {
  return driven ? TopicName(vehicle, "video") : TopicName(vehicle, "video/" + camera);
}
inline std::string VideoFeedbackTopic(const std::string& vehicle, const std::string& camera,
                                      bool driven) {
  return driven ? TopicName(vehicle, "video_feedback")
                : TopicName(vehicle, "video_feedback/" + camera);
}
inline std::string CameraCommandTopic(const std::string& vehicle, const std::string& camera) {
  return TopicName(vehicle, "camera/" + camera);
}
inline std::string CameraStatusTopic(const std::string& vehicle) {
  return TopicName(vehicle, "cameras");
}

/// A steerable camera's command (CameraCommand) and the vehicle's status of
/// its cameras (CameraStatus). The command is an aim, not a rate: no
/// watchdog moves a camera its holder stopped commanding.
struct CameraMessages {
  using Command = CameraAim;
  using CommandMsg = msg::CameraCommand;
  using CommandWriter = link::CameraCommandWriter;
  using CommandReader = link::CameraCommandReader;
  using StatusMsg = msg::CameraStatus;
  using StatusWriter = link::CameraStatusWriter;
  using StatusReader = link::CameraStatusReader;
  static constexpr Profile kCommandProfile = Profile::kCommand;
  static constexpr Profile kStatusProfile = Profile::kLatched;

  /// A float's rounding past a range's end is not malformed.
  static constexpr double kRangeSlack = 1e-3;
  /// The values of `c` for `camera` into `m` (the caller stamps sequence,
  /// time, session and operator).
  static void Encode(const std::string& camera, const Command& c, CommandMsg& m) {
    m.camera(camera);
    m.pan(static_cast<float>(c.pan));
    m.tilt(static_cast<float>(c.tilt));
    m.zoom(static_cast<float>(c.zoom));
  }
  /// The aim in `m` for `camera`, clamped into `range`; false when it was
  /// malformed: another camera's name, non-finite or out of range.
  static bool Decode(const CommandMsg& m, const std::string& camera, const CameraRange& range,
                     Command& out) {
    const CameraAim aim{m.pan(), m.tilt(), m.zoom()};
    out = Clamped(aim, range);
    return m.camera() == camera && InRange(aim, range, kRangeSlack);
  }
};

}  // namespace haptel::link
