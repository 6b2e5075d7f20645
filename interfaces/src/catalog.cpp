#include "haptel/interfaces/catalog.hpp"

#include <deque>
#include <stdexcept>

#include "haptel/config/error.hpp"

namespace haptel::interfaces {

namespace {

/// Every registered interface (a deque: what FindInterface returned stays valid).
std::deque<InterfaceDescriptor>& Catalogue() {
  static std::deque<InterfaceDescriptor> catalogue;
  return catalogue;
}

const InterfaceDescriptor& DescriptorOf(const std::string& name) {
  const InterfaceDescriptor* d = FindInterface(name);
  if (d == nullptr) throw std::logic_error("interface '" + name + "' is not in the catalogue");
  return *d;
}

}  // namespace

void AddInterface(InterfaceDescriptor descriptor) {
  if (!descriptor.load || (!descriptor.make_robot && !descriptor.make_blimp)) {
    throw std::invalid_argument("interface '" + descriptor.kind.name +
                                "': a descriptor needs a loader and a factory");
  }
  RegisterInterfaceKind(descriptor.kind);  // throws when the name is taken
  Catalogue().push_back(std::move(descriptor));
}

const InterfaceDescriptor* FindInterface(const std::string& name) {
  for (const InterfaceDescriptor& d : Catalogue()) {
    if (d.kind.name == name) return &d;
  }
  return nullptr;
}

const InterfaceKindInfo& FirstInterface(VehicleFamily family, InterfaceInput input) {
  for (const InterfaceDescriptor& d : Catalogue()) {
    if (d.kind.family == family && d.kind.input == input) return d.kind;
  }
  throw std::logic_error(std::string("no ") + ToString(family) + " interface takes that input");
}

const InterfaceKindInfo& InterfaceSpec::kind() const { return DescriptorOf(name).kind; }

InterfaceSpec LoadInterfaceSpec(const RunConfig& run, const std::string& name,
                                VehicleFamily family) {
  const std::filesystem::path file = InterfaceFile(run, name);
  const std::string declared = InterfaceName(file);
  const InterfaceDescriptor* d = FindInterface(declared);
  if (d == nullptr) {
    throw ConfigError(file.string() + ": key 'name': expected one of " +
                      InterfaceKindNames(family) + ", got '" + declared + "'");
  }
  if (d->kind.family != family) {
    throw ConfigError(file.string() + ": interface '" + declared + "' " +
                      (d->kind.family == VehicleFamily::kBlimp ? "flies a " : "drives a ") +
                      ToString(d->kind.family) + "; the " + ToString(family) + " is " +
                      (family == VehicleFamily::kBlimp ? "flown" : "driven") + " with " +
                      InterfaceKindNames(family));
  }
  return d->load(file);
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

std::unique_ptr<MediatorInterface> MakeInterface(const InterfaceSpec& spec,
                                                 const InterfaceParts& parts) {
  const InterfaceDescriptor& d = DescriptorOf(spec.name);
  if (!d.make_robot) throw std::logic_error("interface '" + spec.name + "' drives no robot");
  return d.make_robot(spec, parts);
}

std::unique_ptr<BlimpInterface> MakeBlimpInterface(const InterfaceSpec& spec,
                                                   const InterfaceParts& parts) {
  const InterfaceDescriptor& d = DescriptorOf(spec.name);
  if (!d.make_blimp) throw std::logic_error("interface '" + spec.name + "' flies no blimp");
  return d.make_blimp(spec, parts);
}

const InputBox& PersonsInput(const std::string& interface, const InterfaceParts& parts) {
  if (parts.input == nullptr)
    throw std::invalid_argument("interface '" + interface + "' needs a person's input");
  return *parts.input;
}

}  // namespace haptel::interfaces
