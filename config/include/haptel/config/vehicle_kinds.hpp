#pragma once
/// @file The vehicle kinds a vehicle file may name, in one table: each
/// kind's family (what its link carries), the sections of the vehicle file
/// it reads, and a line saying what it is. The vehicle node keeps each
/// kind's adapter factory beside it (vehicles/vehicle_kinds.hpp); nothing
/// else tells kinds apart by their names.
///
/// Adding a kind: a row here (or RegisterVehicleKind at start-up), its
/// adapter and factory in vehicles/, and a vehicle file (docs/vehicles.md).
#include <deque>
#include <string>

namespace haptel {

/// What a vehicle's link carries, and so what drives it on the operator
/// side: the robot's motor levels and ground state (TreadCommand,
/// VehicleState; a track), or the blimp's seven channels and flight state
/// (BlimpCommand, BlimpState; a blimp course).
enum class VehicleFamily { kRobot, kBlimp };
/// "robot" or "blimp".
const char* ToString(VehicleFamily family);

/// The optional sections of a vehicle file a kind reads, besides the common
/// ones (name, world, rates, drive, body, camera, link). A kind that reads a
/// section needs it in its file.
enum VehicleSection : unsigned {
  kNoSection = 0,
  kCanSection = 1U << 0,      ///< `can`: the CAN bus and its nodes
  kAirshipSection = 1U << 1,  ///< `airship`: the simulated airship's model
  kServoSection = 1U << 2,    ///< `servo`: a servo controller and its channels
  kRos2Section = 1U << 3,     ///< `ros2`: a ROS 2 robot's domain and topics
};

struct VehicleKindInfo {
  std::string name;  ///< as a vehicle file's `kind` names it
  VehicleFamily family = VehicleFamily::kRobot;
  unsigned sections = kNoSection;  ///< VehicleSection bits
  std::string summary;             ///< one line, for errors and docs
  /// The vehicle lives in the simulated world the operator side hands it
  /// (its track or course): the operator side knows where everything is,
  /// and can draw the vehicle in it (haptel run --third-person).
  bool simulated = false;
  /// A simulation alone, with no hardware, bus, port or thread of its own:
  /// `haptel run --simulated-time` steps it in the operator's process on
  /// the run's simulated clock.
  bool steps_in_process = false;
  bool Uses(VehicleSection section) const { return (sections & section) != 0; }
};

/// Every kind: the built-in ones, then any registered since (a deque: what
/// FindVehicleKind returned stays valid).
const std::deque<VehicleKindInfo>& VehicleKinds();
/// The kind named `name`, or null.
const VehicleKindInfo* FindVehicleKind(const std::string& name);
/// The kind named `name`; std::invalid_argument naming the known kinds
/// when there is none.
const VehicleKindInfo& VehicleKind(const std::string& name);
/// Adds a kind (a plug-in's, a test's toy kind). Throws
/// std::invalid_argument when the name is taken or is not a kind name
/// (letters, digits and '-'). Register before any thread reads the table.
void RegisterVehicleKind(const VehicleKindInfo& info);
/// "sim-robot, can-robot, …": every kind's name, for an error's "expected".
std::string VehicleKindNames();

}  // namespace haptel
