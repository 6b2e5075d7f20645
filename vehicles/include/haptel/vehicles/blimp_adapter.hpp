#pragma once
/// @file The seam between a blimp node and what it flies: the simulated
/// airship, or the servo controller of the real one (seven channels).
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "haptel/config/reality.hpp"
#include "haptel/config/truth_format.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/core/camera_aim.hpp"

namespace haptel::vehicles {

/// What a blimp adapter knows about its vehicle. The real blimp knows only
/// what it sent (no pose: pose_valid false).
struct BlimpAdapterState {
  bool pose_valid = false;
  double x = 0.0, y = 0.0, z = 0.0;           ///< m, course frame (x east, y north, z up)
  double yaw = 0.0, pitch = 0.0, roll = 0.0;  ///< rad
  double vx = 0.0, vy = 0.0, vz = 0.0;        ///< m/s, ground velocity, course frame
  double airspeed = 0.0;                      ///< m/s
  bool contact = false;                       ///< touching the ground or a building
  double impact_speed = 0.0;                  ///< m/s, closing speed at the latest contact's onset
  uint32_t contacts = 0;                      ///< contact onsets so far
  BlimpCommand applied;                       ///< the channels as applied now
  std::array<double, 7> pulse_us{};  ///< per channel where a servo controller drives them (0: none)
  uint16_t controller_errors = 0;    ///< the servo controller's error register (Maestro bits)
  bool fault = false;
  std::string fault_message;
  /// How long before now the pose was measured (the state's stamp says so).
  double measured_age_s = 0.0;
};

class BlimpAdapter {
 public:
  virtual ~BlimpAdapter() = default;
  /// Sets every channel (the command is in range: the node checked it).
  virtual void Apply(const BlimpCommand& command) = 0;
  /// Every channel to neutral: no power, tail rotor off, surfaces centred,
  /// the helix plane level, the camera straight ahead.
  virtual void Failsafe() { Apply(BlimpCommand{}); }
  /// Points camera `camera` (its index in VehicleConfig::Cameras(); not the
  /// driven one, which the command turns) where its holder asked: its
  /// servos, where it has them. A simulator's head needs nothing.
  virtual void AimCamera(size_t /*camera*/, const CameraAim& /*aim*/) {}
  /// Where camera `camera` points as the vehicle knows it (the servo
  /// controller's outputs read back); false: as it was aimed.
  virtual bool CameraAimed(size_t /*camera*/, CameraAim* /*aim*/) const { return false; }
  /// Advances by dt seconds: simulators step, hardware talks to its controller.
  virtual void Update(double dt) = 0;
  virtual BlimpAdapterState State() const = 0;
  /// A simulator's drawn reality (its truth record's header, its clock);
  /// null: the real blimp.
  virtual const DrawnReality* reality() const { return nullptr; }
  /// Where the blimp truly is (a simulator; false: the real one). The
  /// caller stamps operator_ns.
  virtual bool Truth(TruthRow*) const { return false; }
};

}  // namespace haptel::vehicles
