#include "haptel/haptics/device_factory.hpp"

#include "haptel/haptics/device_drivers.hpp"

namespace haptel::haptics {

std::unique_ptr<Device> MakeDevice(const DeviceConfig& config, const OperatorConfig& muscle) {
  config.ValidateOrThrow();
  return DriverOf(config).make(config, muscle);
}

}  // namespace haptel::haptics
