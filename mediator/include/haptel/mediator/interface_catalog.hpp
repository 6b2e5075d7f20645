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
#include "haptel/config/keyboard.hpp"
#include "haptel/config/run.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::interfaces {
class ControlsPort;
}

namespace haptel::mediator {

/// One interface file, loaded: its config says which interface it is.
struct InterfaceSpec {
  std::string name;
  std::variant<GestureConfig, CockpitConfig, KeyboardConfig, GamepadConfig> config;

  bool is_cockpit() const { return std::holds_alternative<CockpitConfig>(config); }
  /// The interface moves proxy hands among bodies (a physics world).
  bool needs_physics() const { return is_cockpit(); }
  /// Hands the interface uses ([left, right]).
  std::array<bool, 2> hands() const;
  /// Driven by a person's keys or controller, not by hands on a device.
  bool manual() const { return is_keyboard() || is_gamepad(); }
  bool is_keyboard() const { return std::holds_alternative<KeyboardConfig>(config); }
  bool is_gamepad() const { return std::holds_alternative<GamepadConfig>(config); }
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
};

/// Builds the interface. Throws std::invalid_argument when a part it needs is missing.
std::unique_ptr<interfaces::MediatorInterface> MakeInterface(const InterfaceSpec& spec, const InterfaceParts& parts);

}  // namespace haptel::mediator
