#include "haptel/mediator/interface_catalog.hpp"

#include <map>
#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/cockpit.hpp"
#include "haptel/interfaces/gamepad.hpp"
#include "haptel/interfaces/gesture.hpp"
#include "haptel/interfaces/keyboard.hpp"

namespace haptel::mediator {

const InterfaceKindInfo& InterfaceSpec::kind() const {
  const InterfaceKindInfo* kind = FindInterfaceKind(name);
  if (kind == nullptr) throw std::logic_error("interface '" + name + "' is not in the interface table");
  return *kind;
}

double InterfaceSpec::command_rate_hz() const {
  return std::visit([](const auto& c) { return c.command_rate_hz; }, config);
}

namespace {

/// Each robot interface's config loader, beside its row in the interface table.
using Loader = InterfaceSpec::Config (*)(const std::filesystem::path&);
const std::map<std::string, Loader>& Loaders() {
  static const std::map<std::string, Loader> loaders{
      {"gesture", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadGesture(f); }},
      {"cockpit", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadCockpit(f); }},
      {"cockpit-hud", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadCockpit(f); }},
      {"cockpit-assisted", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadCockpit(f); }},
      {"keyboard", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadKeyboard(f); }},
      {"gamepad", [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadGamepad(f); }},
  };
  return loaders;
}

}  // namespace

InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name) {
  const std::filesystem::path file = InterfaceFile(run, name);
  const std::string declared = InterfaceName(file);
  const InterfaceKindInfo* kind = FindInterfaceKind(declared);
  if (kind == nullptr) {
    throw ConfigError(file.string() + ": key 'name': expected one of " + InterfaceKindNames(VehicleFamily::kRobot) +
                      ", got '" + declared + "'");
  }
  if (kind->family != VehicleFamily::kRobot) {
    throw ConfigError(file.string() + ": interface '" + declared + "' flies a " + ToString(kind->family) +
                      "; the robot is driven with " + InterfaceKindNames(VehicleFamily::kRobot));
  }
  const auto loader = Loaders().find(declared);
  if (loader == Loaders().end()) {
    throw std::logic_error("interface '" + declared + "' has no loader in the interface catalog");
  }
  InterfaceSpec spec;
  spec.name = declared;
  spec.config = loader->second(file);
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
