#include "haptel/haptics/device_drivers.hpp"

#include <deque>
#include <stdexcept>

namespace haptel::haptics {

namespace {

std::deque<DeviceDriver>& Drivers() {
  static std::deque<DeviceDriver> drivers;
  return drivers;
}

}  // namespace

RegisterDeviceDriver::RegisterDeviceDriver(DeviceDriver driver) {
  if (driver.name.empty() || !driver.make)
    throw std::invalid_argument("device driver '" + driver.name + "': a name and a factory");
  // config/ checks the device files: it learns the name and the driver's own checks here.
  AddDeviceDriverCheck(driver.name, driver.check);  // throws when the name is taken
  Drivers().push_back(std::move(driver));
}

const DeviceDriver* FindDeviceDriver(const std::string& name) {
  for (const DeviceDriver& d : Drivers()) {
    if (d.name == name) return &d;
  }
  return nullptr;
}

const DeviceDriver& DriverOf(const DeviceConfig& device) {
  const DeviceDriver* d = FindDeviceDriver(device.driver);
  if (d == nullptr) {
    throw std::logic_error("device '" + device.name + "': no driver '" + device.driver +
                           "' is registered");
  }
  return *d;
}

std::string DeviceUnavailable(const DeviceConfig& device) {
  const DeviceDriver& driver = DriverOf(device);
  return driver.available ? driver.available(device) : std::string{};
}

}  // namespace haptel::haptics
