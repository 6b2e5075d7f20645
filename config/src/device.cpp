#include "haptel/config/device.hpp"

#include <functional>
#include <map>
#include <stdexcept>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

/// The registered drivers' own checks, by name (AddDeviceDriverCheck).
std::map<std::string, std::function<void(const DeviceConfig&)>>& DriverChecks() {
  static std::map<std::string, std::function<void(const DeviceConfig&)>> checks;
  return checks;
}

/// "replay, sim, udp": the registered drivers, for an error's "expected".
std::string DriverNames() {
  std::string names;
  for (const auto& [name, check] : DriverChecks()) names += (names.empty() ? "" : ", ") + name;
  return names;
}
}  // namespace

void AddDeviceDriverCheck(const std::string& driver,
                          std::function<void(const DeviceConfig&)> check) {
  if (!DriverChecks().emplace(driver, std::move(check)).second)
    throw std::invalid_argument("device driver '" + driver + "' is registered already");
}

void ServoLoopConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void SafetyConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (setpoint_timeout_s + fade_s > 0.05 + 1e-9) {
    check::Fail("fade_s",
                "setpoint_timeout_s + fade_s <= 0.05 (forces must be gone 50 ms after a stall)",
                {"setpoint_timeout_s"});
  }
}

void SimArmConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  for (int i = 0; i < 3; ++i) {
    if (workspace_min[i] >= workspace_max[i]) {
      check::Fail("workspace_max", "workspace_min < workspace_max on every axis",
                  {"workspace_min"});
    }
  }
}

void UdpArmEndpoint::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void UdpDeviceConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void ReplayDeviceConfig::ValidateOrThrow() const {}

void MouseDeviceConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void SdlFfAxisMap::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void SdlFfRimMap::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void SdlFfHandMap::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (rim.axis >= 0 && (y.axis >= 0 || z.axis >= 0 || y.reverse_axis >= 0 || z.reverse_axis >= 0)) {
    check::Fail("rim.axis", "a rim moves y and z: y.axis and z.axis at -1 (or no rim: -1)",
                {y.axis >= 0 ? "y.axis" : "z.axis"});
  }
}

void SdlFfDeadman::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if ((button >= 0) == (axis >= 0)) {
    check::Fail("button", "exactly one of 'button' and 'axis' (the other -1): the deadman",
                {"axis"});
  }
}

void SdlFfDeviceConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void DeviceConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  const auto driver_check = DriverChecks().find(driver);
  if (driver_check == DriverChecks().end()) check::Fail("driver", "one of: " + DriverNames());
  if (!sides[0] && !sides[1]) check::Fail("sides", "at least one of 'left', 'right'");
  if (driver_check->second) driver_check->second(*this);
}

DeviceConfig LoadDevice(const std::filesystem::path& file) {
  return config_detail::LoadFile<DeviceConfig>(file, [](YamlMap& root, DeviceConfig& d) {
    const std::vector<std::string> sides = root.Strings("sides", {"left", "right"});
    d.sides = {false, false};
    for (const std::string& s : sides) {
      if (s == "left") {
        d.sides[0] = true;
      } else if (s == "right") {
        d.sides[1] = true;
      } else {
        root.Fail("sides", "a list of 'left' and/or 'right'");
      }
    }
  });
}

}  // namespace haptel
