#include "haptel/config/interface_kinds.hpp"

#include <stdexcept>

namespace haptel {

namespace {

std::deque<InterfaceKindInfo>& Table() {
  using F = VehicleFamily;
  using I = InterfaceInput;
  static std::deque<InterfaceKindInfo> kinds{
      {"gesture",
       F::kRobot,
       {false, true},
       I::kHands,
       false,
       "no controls: the right hand's offset drives the motors, a field pulls it to neutral"},
      {"gesture-shared",
       F::kRobot,
       {false, true},
       I::kHands,
       false,
       "gesture with haptic shared control: a bounded push away from commands that lead into an "
       "obstacle"},
      {"cockpit",
       F::kRobot,
       {true, true},
       I::kHands,
       true,
       "a steering wheel and a throttle lever to grasp"},
      {"cockpit-hud",
       F::kRobot,
       {true, true},
       I::kHands,
       true,
       "the cockpit with a speedometer and turn indicators"},
      {"cockpit-assisted",
       F::kRobot,
       {true, true},
       I::kHands,
       true,
       "the cockpit whose controls return to zero when released"},
      {"cockpit-shared",
       F::kRobot,
       {true, true},
       I::kHands,
       true,
       "the cockpit with haptic shared control: the wheel and lever pushed away from a steer into "
       "an obstacle"},
      {"keyboard",
       F::kRobot,
       {false, false},
       I::kKeys,
       false,
       "a person's arrow keys (or W/A/S/D)"},
      {"gamepad", F::kRobot, {false, false}, I::kGamepad, false, "a person's game controller"},
      {"blimp-gesture",
       F::kBlimp,
       {true, true},
       I::kHands,
       false,
       "the blimp's gesture cockpit: the right hand steers, the left gives power"},
      {"blimp-keys", F::kBlimp, {false, false}, I::kKeys, false, "the blimp by a person's keys"},
      {"blimp-gamepad",
       F::kBlimp,
       {false, false},
       I::kGamepad,
       false,
       "the blimp by a person's game controller"},
  };
  return kinds;
}

}  // namespace

const std::deque<InterfaceKindInfo>& InterfaceKinds() { return Table(); }

const InterfaceKindInfo* FindInterfaceKind(const std::string& name) {
  for (const InterfaceKindInfo& kind : Table()) {
    if (kind.name == name) return &kind;
  }
  return nullptr;
}

void RegisterInterfaceKind(const InterfaceKindInfo& info) {
  if (info.name.empty()) throw std::invalid_argument("interface kind: no name");
  if (FindInterfaceKind(info.name) != nullptr) {
    throw std::invalid_argument("interface '" + info.name + "' is registered already");
  }
  Table().push_back(info);
}

std::string InterfaceKindNames(VehicleFamily family) {
  std::string names;
  for (const InterfaceKindInfo& kind : Table()) {
    if (kind.family == family) names += (names.empty() ? "" : ", ") + kind.name;
  }
  return names;
}

}  // namespace haptel
