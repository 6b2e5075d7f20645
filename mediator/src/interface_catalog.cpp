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
  if (kind == nullptr)
    throw std::logic_error("interface '" + name + "' is not in the interface table");
  return *kind;
}

double InterfaceSpec::command_rate_hz() const {
  return std::visit([](const auto& c) { return c.command_rate_hz; }, config);
}

namespace {

/// A robot interface's loader and factory, beside its row in the interface table.
struct CatalogEntry {
  InterfaceSpec::Config (*load)(const std::filesystem::path& file);
  std::unique_ptr<interfaces::MediatorInterface> (*make)(const InterfaceSpec& spec,
                                                         const InterfaceParts& parts);
};

const interfaces::InputBox& PersonsInput(const InterfaceSpec& spec, const InterfaceParts& parts) {
  if (parts.input == nullptr)
    throw std::invalid_argument("interface '" + spec.name + "' needs a person's input");
  return *parts.input;
}

const CatalogEntry kGesture{
    [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadGesture(f); },
    [](const InterfaceSpec& spec,
       const InterfaceParts& parts) -> std::unique_ptr<interfaces::MediatorInterface> {
      return std::make_unique<interfaces::GestureInterface>(std::get<GestureConfig>(spec.config),
                                                            parts.vehicle);
    }};
const CatalogEntry kCockpit{
    [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadCockpit(f); },
    [](const InterfaceSpec& spec,
       const InterfaceParts& parts) -> std::unique_ptr<interfaces::MediatorInterface> {
      if (parts.controls == nullptr)
        throw std::invalid_argument("interface '" + spec.name + "' needs its controls");
      return std::make_unique<interfaces::CockpitInterface>(
          std::get<CockpitConfig>(spec.config), *parts.controls, interfaces::GripGeometry{},
          parts.vehicle);
    }};
const CatalogEntry kKeyboard{
    [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadKeyboard(f); },
    [](const InterfaceSpec& spec,
       const InterfaceParts& parts) -> std::unique_ptr<interfaces::MediatorInterface> {
      return std::make_unique<interfaces::KeyboardInterface>(
          std::get<KeyboardConfig>(spec.config), PersonsInput(spec, parts), parts.speed_levels);
    }};
const CatalogEntry kGamepad{
    [](const std::filesystem::path& f) -> InterfaceSpec::Config { return LoadGamepad(f); },
    [](const InterfaceSpec& spec,
       const InterfaceParts& parts) -> std::unique_ptr<interfaces::MediatorInterface> {
      return std::make_unique<interfaces::GamepadInterface>(std::get<GamepadConfig>(spec.config),
                                                            PersonsInput(spec, parts));
    }};

/// The robot family's interfaces by name (the blimp's are its session's).
const std::map<std::string, const CatalogEntry*>& Catalog() {
  static const std::map<std::string, const CatalogEntry*> catalog{
      {"gesture", &kGesture},     {"gesture-shared", &kGesture},   {"cockpit", &kCockpit},
      {"cockpit-hud", &kCockpit}, {"cockpit-assisted", &kCockpit}, {"cockpit-shared", &kCockpit},
      {"keyboard", &kKeyboard},   {"gamepad", &kGamepad},
  };
  return catalog;
}

const CatalogEntry& EntryFor(const std::string& name) {
  const auto entry = Catalog().find(name);
  if (entry == Catalog().end()) {
    throw std::logic_error("interface '" + name +
                           "' has no loader and factory in the interface catalog");
  }
  return *entry->second;
}

}  // namespace

InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name) {
  const std::filesystem::path file = InterfaceFile(run, name);
  const std::string declared = InterfaceName(file);
  const InterfaceKindInfo* kind = FindInterfaceKind(declared);
  if (kind == nullptr) {
    throw ConfigError(file.string() + ": key 'name': expected one of " +
                      InterfaceKindNames(VehicleFamily::kRobot) + ", got '" + declared + "'");
  }
  if (kind->family != VehicleFamily::kRobot) {
    throw ConfigError(file.string() + ": interface '" + declared + "' flies a " +
                      ToString(kind->family) + "; the robot is driven with " +
                      InterfaceKindNames(VehicleFamily::kRobot));
  }
  InterfaceSpec spec;
  spec.name = declared;
  spec.config = EntryFor(declared).load(file);
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

std::unique_ptr<interfaces::MediatorInterface> MakeInterface(const InterfaceSpec& spec,
                                                             const InterfaceParts& parts) {
  return EntryFor(spec.name).make(spec, parts);
}

}  // namespace haptel::mediator
