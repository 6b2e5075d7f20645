#include "haptel/config/device.hpp"

#include "archives.hpp"
#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {
/// The sides as the file names them: [left, right].
constexpr const char* kSideNames[2] = {"left", "right"};
}  // namespace

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

void DeviceConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (driver != "sim" && driver != "udp" && driver != "replay") {
    check::Fail("driver", "one of: sim, udp, replay");
  }
  if (!sides[0] && !sides[1]) check::Fail("sides", "at least one of 'left', 'right'");
  if (driver == "udp") {
    for (int i = 0; i < 2; ++i) {
      const UdpArmEndpoint& arm = udp.arms[i];
      if (sides[i] && arm.port == 0) {
        check::Fail(std::string("udp.") + kSideNames[i] + ".port",
                    std::string("a port in [1, 65535] for the ") + kSideNames[i] +
                        " arm of the udp driver (now " + arm.host + ":0)");
      }
    }
  }
  if (driver == "replay" && replay.trace.empty()) {
    check::Fail("replay.trace", "a trace file for the replay driver");
  }
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
