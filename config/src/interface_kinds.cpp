#include "haptel/config/interface_kinds.hpp"

#include <stdexcept>
#include <vector>

namespace haptel {

namespace {

/// Filled as the interfaces register (interfaces/catalog.hpp), each beside its code.
std::deque<InterfaceKindInfo>& Table() {
  static std::deque<InterfaceKindInfo> kinds;
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

bool LoadsInto(const std::string& name, const std::type_info& config) {
  const InterfaceKindInfo* kind = FindInterfaceKind(name);
  return kind != nullptr && kind->config != nullptr && *kind->config == config;
}

std::string NamesLoadingInto(const std::type_info& config) {
  std::vector<std::string> names;
  for (const InterfaceKindInfo& kind : Table()) {
    if (kind.config != nullptr && *kind.config == config) names.push_back(kind.name);
  }
  if (names.empty()) {
    // The table is filled by the interfaces' registrations: a program that
    // loads an interface file without linking haptel_interfaces has none.
    throw std::logic_error(std::string("no interface loads into ") + config.name() +
                           ": link haptel_interfaces (the interface catalogue)");
  }
  if (names.size() == 1) return "'" + names[0] + "'";
  if (names.size() == 2) return "'" + names[0] + "' or '" + names[1] + "'";
  std::string list;
  for (const std::string& name : names) list += (list.empty() ? "" : ", ") + name;
  return "one of: " + list;
}

std::string InterfaceKindNames(VehicleFamily family) {
  std::string names;
  for (const InterfaceKindInfo& kind : Table()) {
    if (kind.family == family) names += (names.empty() ? "" : ", ") + kind.name;
  }
  return names;
}

}  // namespace haptel
