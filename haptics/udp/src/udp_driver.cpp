// The `udp` driver in the device registry (haptel/haptics/device_drivers.hpp):
// one computer per arm over UDP (udp_device.hpp, PROTOCOL.md).
#include <string>

#include "haptel/config/check.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/udp/udp_device.hpp"

namespace haptel::haptics {
namespace {

/// Every side the device uses has a port to reach its arm at.
void CheckPorts(const DeviceConfig& config) {
  constexpr const char* kSideNames[2] = {"left", "right"};
  for (int i = 0; i < 2; ++i) {
    const UdpArmEndpoint& arm = config.udp.arms[i];
    if (config.sides[i] && arm.port == 0) {
      config_check::Fail(std::string("udp.") + kSideNames[i] + ".port",
                         std::string("a port in [1, 65535] for the ") + kSideNames[i] +
                             " arm of the udp driver (now " + arm.host + ":0)");
    }
  }
}

const RegisterDeviceDriver kUdpDriver{{
    .name = UdpDevice::kDriver,
    .simulated = false,
    .reads_trace = false,
    .reads_window = false,
    .calibration = CalibrationSource::kMeasured,
    .check = CheckPorts,
    .available = nullptr,
    .make = [](const DeviceConfig& config, const OperatorConfig&) -> std::unique_ptr<Device> {
      return std::make_unique<UdpDevice>(config);
    },
}};

}  // namespace
}  // namespace haptel::haptics
