#include "haptel/mediator/interface_catalog.hpp"

#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/gamepad.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/interfaces/keyboard.hpp"

namespace haptel::mediator {

std::array<bool, 2> InterfaceSpec::hands() const {
  if (is_cockpit()) return {true, true};
  if (std::holds_alternative<GestureConfig>(config)) return {false, true};
  return {false, false};
}

double InterfaceSpec::command_rate_hz() const {
  return std::visit([](const auto& c) { return c.command_rate_hz; }, config);
}

InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name) {
  const std::filesystem::path file = InterfaceFile(run, name);
  const std::string kind = InterfaceName(file);
  InterfaceSpec spec;
  spec.name = kind;
  if (kind.rfind("blimp-", 0) == 0) {
    throw ConfigError(file.string() + ": interface '" + kind + "' flies a blimp; the robot is driven with " +
                      "gesture, a cockpit, keyboard or gamepad");
  }
  if (kind.rfind("cockpit", 0) == 0) {
    spec.config = LoadCockpit(file);
  } else if (kind == "keyboard") {
    spec.config = LoadKeyboard(file);
  } else if (kind == "gamepad") {
    spec.config = LoadGamepad(file);
  } else {
    spec.config = LoadGesture(file);
  }
  return spec;
}

void CheckHands(const std::vector<InterfaceSpec>& specs, const DeviceConfig& device) {
  const char* names[2] = {"left", "right"};
  std::string has;
  for (int s = 0; s < 2; ++s) {
    if (device.sides[s]) has += std::string(has.empty() ? "" : ", ") + names[s];
  }
  for (const InterfaceSpec& spec : specs) {
    for (int s = 0; s < 2; ++s) {
      if (!spec.hands()[s] || device.sides[s]) continue;
      throw ConfigError(device.file.string() + ": key 'sides': expected the " + names[s] +
                        " arm, which interface '" + spec.name + "' uses, got [" + has +
                        "]; use a device with that arm, or another interface (--interface, or "
                        "the run configuration's 'switchable_interfaces')");
    }
  }
}

std::unique_ptr<interfaces::MediatorInterface> MakeInterface(const InterfaceSpec& spec, const InterfaceParts& parts) {
  if (const auto* cockpit = std::get_if<CockpitConfig>(&spec.config)) {
    if (parts.controls == nullptr) throw std::invalid_argument("interface '" + spec.name + "' needs its controls");
    return std::make_unique<interfaces::CockpitInterface>(*cockpit, *parts.controls);
  }
  if (const auto* keyboard = std::get_if<KeyboardConfig>(&spec.config)) {
    if (parts.input == nullptr) throw std::invalid_argument("interface '" + spec.name + "' needs a person's input");
    return std::make_unique<interfaces::KeyboardInterface>(*keyboard, *parts.input, parts.speed_levels);
  }
  if (const auto* gamepad = std::get_if<GamepadConfig>(&spec.config)) {
    if (parts.input == nullptr) throw std::invalid_argument("interface '" + spec.name + "' needs a person's input");
    return std::make_unique<interfaces::GamepadInterface>(*gamepad, *parts.input);
  }
  return std::make_unique<interfaces::GestureInterface>(std::get<GestureConfig>(spec.config));
}

}  // namespace haptel::mediator
