#pragma once
/// @file The interfaces a session can run, read from their files and built
/// for the session's parts (physics controls, a person's input).
#include <filesystem>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/device.hpp"
#include "haptel/config/gamepad.hpp"
#include "haptel/config/gesture.hpp"
#include "haptel/config/interface_kinds.hpp"
#include "haptel/config/keyboard.hpp"
#include "haptel/config/run.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"
#include "haptel/interfaces/shared_control.hpp"

namespace haptel::interfaces {
class ControlsPort;
}

namespace haptel::mediator {

/// One interface file of the robot family, loaded: its row in the interface
/// table (config/interface_kinds.hpp) says what it is, its config how it is set.
struct InterfaceSpec {
  using Config = std::variant<GestureConfig, CockpitConfig, KeyboardConfig, GamepadConfig>;
  std::string name;
  Config config;

  /// Its row in the interface table.
  const InterfaceKindInfo& kind() const;
  bool is_cockpit() const { return std::holds_alternative<CockpitConfig>(config); }
  /// The interface moves proxy hands among bodies (a physics world).
  bool needs_physics() const { return kind().physics; }
  /// Hands the interface uses ([left, right]).
  std::array<bool, 2> hands() const { return kind().hands; }
  /// Driven by a person's keys or controller, not by hands on a device.
  bool manual() const { return kind().manual(); }
  bool is_keyboard() const { return kind().input == InterfaceInput::kKeys; }
  bool is_gamepad() const { return kind().input == InterfaceInput::kGamepad; }
  double command_rate_hz() const;
};

/// Loads `<interfaces_dir>/<name>.yaml` (ConfigError naming the file otherwise).
InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name);

/// Throws ConfigError, naming the device file and its key 'sides', when one of
/// the interfaces a run builds uses a hand the device has no arm for (the
/// gesture interface the right, the cockpits both; keys and controllers none).
void CheckHands(const std::vector<InterfaceSpec>& specs, const DeviceConfig& device);

/// What an interface is built on.
struct InterfaceParts {
  interfaces::ControlsPort* controls = nullptr;  ///< a cockpit's controls (physics)
  const interfaces::InputBox* input = nullptr;   ///< a person's keys and controller
  int speed_levels = 8;                          ///< the vehicle's levels per direction
  /// The vehicle's drive and body, for shared control's prediction (gesture-shared,
  /// cockpit-shared).
  interfaces::VehicleGeometry vehicle;
};

/// Builds the interface. Throws std::invalid_argument when a part it needs is missing.
std::unique_ptr<interfaces::MediatorInterface> MakeInterface(const InterfaceSpec& spec,
                                                             const InterfaceParts& parts);

}  // namespace haptel::mediator
