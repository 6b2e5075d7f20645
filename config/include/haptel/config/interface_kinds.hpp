#pragma once
/// @file The mediator interfaces a run or a study may name, in one table:
/// the vehicle family each drives, the device's arms it uses, how its input
/// comes (hands on the device, a person's keys or game controller) and
/// whether its controls are bodies in a physics world. The loaders and the
/// run's checks read this table instead of telling interfaces apart by name.
/// config/ is below the interfaces, so the table holds no row of its own:
/// each interface's descriptor, registered beside its code, adds its row
/// (interfaces/catalog.hpp), and a program that loads study or fleet files
/// links the interfaces.
#include <array>
#include <deque>
#include <string>
#include <typeinfo>

#include "haptel/config/vehicle_kinds.hpp"

namespace haptel {

/// How an interface takes its input.
enum class InterfaceInput {
  kHands,    ///< both or one hand on the haptic device
  kKeys,     ///< a person's keyboard, in the view's window
  kGamepad,  ///< a person's game controller
};

struct InterfaceKindInfo {
  std::string name;  ///< as its file names it (`name:`), and the file's stem
  VehicleFamily family = VehicleFamily::kRobot;
  std::array<bool, 2> hands{false, false};  ///< the device's arms it uses: [left, right]
  InterfaceInput input = InterfaceInput::kHands;
  /// Its controls are bodies the proxy hands move (a physics world).
  bool physics = false;
  /// Its file carries a `shared_control:` section (gesture-shared,
  /// cockpit-shared: the base interface with haptic shared control).
  bool shared_control = false;
  std::string summary;  ///< one line
  /// The config struct its file loads into (set by the catalogue's
  /// RegisterInterface); the loaders accept a file's `name:` by it.
  const std::type_info* config = nullptr;
  /// Driven by a person's keys or controller, not by hands on a device
  /// (the automatic operator cannot drive it).
  bool manual() const { return input != InterfaceInput::kHands; }
};

/// Every interface, in the order registered (a deque: what FindInterfaceKind
/// returned stays valid).
const std::deque<InterfaceKindInfo>& InterfaceKinds();
/// The interface named `name`, or null.
const InterfaceKindInfo* FindInterfaceKind(const std::string& name);
/// Adds an interface's row: the interface catalogue does, as each interface
/// registers (interfaces/catalog.hpp). std::invalid_argument when the name is
/// taken. Register before any thread reads the table.
void RegisterInterfaceKind(const InterfaceKindInfo& info);
/// "gesture, cockpit, …": the interfaces that drive `family`, for an error's "expected".
std::string InterfaceKindNames(VehicleFamily family);
/// Whether `name` is an interface whose file loads into `config`.
bool LoadsInto(const std::string& name, const std::type_info& config);
/// What a file loading into `config` may be named, for an error's
/// "expected": "'keyboard'", "'gesture' or 'gesture-shared'", "one of:
/// cockpit, cockpit-hud, …".
std::string NamesLoadingInto(const std::type_info& config);

}  // namespace haptel
