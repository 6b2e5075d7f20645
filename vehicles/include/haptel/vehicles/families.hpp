#pragma once
/// @file What a vehicle node does differently per family (VehicleFamily:
/// what the link carries; its messages and range check are link's
/// families.hpp) — and nothing else: the adapter it drives and how it is
/// made safe, the camera's pose and the family's fields of the state
/// message. The node (VehicleNodeOf), its threads, watchdog, ownership and
/// counters are written once over these traits.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "haptel/config/blimp_course.hpp"
#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/link/families.hpp"
#include "haptel/vehicles/adapter.hpp"
#include "haptel/vehicles/blimp_adapter.hpp"
#include "haptel/video/camera_source.hpp"
#include "haptel/video/synthetic_camera.hpp"

namespace haptel::vehicles {

/// The robot family: motor levels for two treads (TreadCommand), the
/// ground state (VehicleState), a VehicleAdapter, a track for its world.
struct RobotFamily : link::RobotMessages {
  using World = Track;
  using Adapter = VehicleAdapter;
  using AdapterState = vehicles::AdapterState;
  /// Said when the watchdog trips, and at the end.
  static constexpr const char* kMadeSafe = "motors stopped";
  static constexpr const char* kAtRest = "motors off";

  /// Nothing moves before the first command: the motors start at rest.
  static void Prepare(Adapter&) {}
  static void Apply(Adapter& adapter, const Command& c, const VehicleConfig& config) {
    adapter.SetMotors({models::QuantiseCommand(c.left, config.drive.speed_levels),
                       models::QuantiseCommand(c.right, config.drive.speed_levels)});
  }
  /// Hardware: zero velocity, then idle.
  static void MakeSafe(Adapter& adapter) { adapter.Stop(); }
  /// A robot's further cameras have no servos: they look as they are aimed.
  static void AimCamera(Adapter&, size_t, const CameraAim&) {}
  static bool CameraAimed(const Adapter&, size_t, CameraAim*) { return false; }
  static video::CameraPose CameraPoseOf(const AdapterState& s) {
    return {.x = s.x, .y = s.y, .heading = s.heading};
  }
  /// The family's own fields of the state; `watchdog_expired` is the node's.
  static void FillState(const AdapterState& s, bool watchdog_expired, StateMsg& m) {
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
    m.watchdog_tripped(watchdog_expired);
    m.range_angle_min(static_cast<float>(s.ranges.angle_min));
    m.range_angle_increment(static_cast<float>(s.ranges.angle_increment));
    m.range_max(static_cast<float>(s.ranges.range_max));
    m.ranges().assign(s.ranges.ranges.begin(), s.ranges.ranges.begin() + s.ranges.count);
  }
};

/// The blimp family: seven channels (BlimpCommand), the flight state
/// (BlimpState), a BlimpAdapter, a blimp course for its world.
struct BlimpFamily : link::BlimpMessages {
  using World = BlimpCourseConfig;
  using Adapter = BlimpAdapter;
  using AdapterState = BlimpAdapterState;
  static constexpr const char* kMadeSafe = "every channel to neutral";
  static constexpr const char* kAtRest = "every channel at neutral";

  /// Nothing flies before the first command.
  static void Prepare(Adapter& adapter) { adapter.Failsafe(); }
  static void Apply(Adapter& adapter, const Command& c, const VehicleConfig&) { adapter.Apply(c); }
  static void MakeSafe(Adapter& adapter) { adapter.Failsafe(); }
  /// A further camera's pan, tilt and zoom: to its servos, where it has them.
  static void AimCamera(Adapter& adapter, size_t camera, const CameraAim& aim) {
    adapter.AimCamera(camera, aim);
  }
  static bool CameraAimed(const Adapter& adapter, size_t camera, CameraAim* aim) {
    return adapter.CameraAimed(camera, aim);
  }
  /// The camera looks where its head points, from the vehicle's pose.
  static video::CameraPose CameraPoseOf(const AdapterState& s) {
    return {.x = s.x,
            .y = s.y,
            .heading = s.yaw,
            .z = s.z,
            .pitch = s.pitch,
            .roll = s.roll,
            .pan = s.applied.camera_pan,
            .tilt = s.applied.camera_tilt};
  }
  static void FillState(const AdapterState& s, bool watchdog_expired, StateMsg& m) {
    m.pose_valid(s.pose_valid);
    m.x(static_cast<float>(s.x));
    m.y(static_cast<float>(s.y));
    m.z(static_cast<float>(s.z));
    m.yaw(static_cast<float>(s.yaw));
    m.pitch(static_cast<float>(s.pitch));
    m.roll(static_cast<float>(s.roll));
    m.vx(static_cast<float>(s.vx));
    m.vy(static_cast<float>(s.vy));
    m.vz(static_cast<float>(s.vz));
    m.airspeed(static_cast<float>(s.airspeed));
    m.contact(s.contact);
    m.impact_speed(static_cast<float>(s.impact_speed));
    m.contacts(s.contacts);
    const BlimpCommand& a = s.applied;
    m.outputs({static_cast<float>(a.elevator), static_cast<float>(a.rudder),
               static_cast<float>(a.power), static_cast<float>(a.helix),
               static_cast<float>(a.tail_rotor), static_cast<float>(a.camera_pan),
               static_cast<float>(a.camera_tilt)});
    std::array<float, 7> pulses{};
    for (size_t i = 0; i < pulses.size(); ++i) pulses[i] = static_cast<float>(s.pulse_us[i]);
    m.pulse_us(pulses);
    m.failsafe(watchdog_expired);
    m.controller_errors(s.controller_errors);
  }
};

}  // namespace haptel::vehicles
