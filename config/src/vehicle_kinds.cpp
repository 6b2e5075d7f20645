#include "haptel/config/vehicle_kinds.hpp"

#include <algorithm>
#include <stdexcept>

namespace haptel {

namespace {

std::deque<VehicleKindInfo>& Table() {
  static std::deque<VehicleKindInfo> kinds{
      {"sim-robot", VehicleFamily::kRobot, kNoSection, "the simulated Lego-style tank", true, true},
      {"can-robot", VehicleFamily::kRobot, kCanSection,
       "the tank's ODrive motors and bumper node on SocketCAN"},
      {"can-robot-sim", VehicleFamily::kRobot, kCanSection,
       "the simulated tank behind emulated CAN nodes, through the real CAN adapter", true},
      {"ros2", VehicleFamily::kRobot, kRos2Section,
       "any ROS 2 differential-drive robot, through its topics"},
      {"sim-blimp", VehicleFamily::kBlimp, kAirshipSection, "the simulated airship", true},
      {"servo-blimp", VehicleFamily::kBlimp, kServoSection,
       "the real blimp's servo controller on a serial port"},
      {"servo-blimp-sim", VehicleFamily::kBlimp, kServoSection | kAirshipSection,
       "the simulated airship behind a simulated servo controller on a pseudo-terminal", true},
  };
  return kinds;
}

bool IsKindName(const std::string& name) {
  return !name.empty() && name.size() <= 64 && name.front() != '-' &&
         std::all_of(name.begin(), name.end(), [](char c) {
           return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                  c == '-';
         });
}

}  // namespace

const char* ToString(VehicleFamily family) {
  return family == VehicleFamily::kBlimp ? "blimp" : "robot";
}

const std::deque<VehicleKindInfo>& VehicleKinds() { return Table(); }

const VehicleKindInfo* FindVehicleKind(const std::string& name) {
  for (const VehicleKindInfo& kind : Table()) {
    if (kind.name == name) return &kind;
  }
  return nullptr;
}

const VehicleKindInfo& VehicleKind(const std::string& name) {
  const VehicleKindInfo* kind = FindVehicleKind(name);
  if (kind == nullptr) {
    throw std::invalid_argument("vehicle kind '" + name +
                                "' is unknown; expected one of: " + VehicleKindNames());
  }
  return *kind;
}

void RegisterVehicleKind(const VehicleKindInfo& info) {
  if (!IsKindName(info.name)) {
    throw std::invalid_argument("vehicle kind '" + info.name +
                                "': expected letters, digits and '-'");
  }
  if (FindVehicleKind(info.name) != nullptr) {
    throw std::invalid_argument("vehicle kind '" + info.name + "' is registered already");
  }
  Table().push_back(info);
}

std::string VehicleKindNames() {
  std::string names;
  for (const VehicleKindInfo& kind : Table()) names += (names.empty() ? "" : ", ") + kind.name;
  return names;
}

}  // namespace haptel
