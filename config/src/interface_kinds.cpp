#include "haptel/config/interface_kinds.hpp"

#include <stdexcept>

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

std::string InterfaceKindNames(VehicleFamily family) {
  std::string names;
  for (const InterfaceKindInfo& kind : Table()) {
    if (kind.family == family) names += (names.empty() ? "" : ", ") + kind.name;
  }
  return names;
}

}  // namespace haptel
