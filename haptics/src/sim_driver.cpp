// The `sim` driver in the device registry (device_drivers.hpp): two simulated
// arms a simulated operator moves (sim_device.hpp).
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/sim_device.hpp"

namespace haptel::haptics {
namespace {

const RegisterDeviceDriver kSimDriver{{
    .name = "sim",
    .simulated = true,
    .reads_trace = false,
    .reads_window = false,
    .calibration = CalibrationSource::kOptional,
    .check = nullptr,
    .available = nullptr,
    .make = [](const DeviceConfig& config, const OperatorConfig& muscle)
        -> std::unique_ptr<Device> { return std::make_unique<SimDevice>(config, muscle); },
}};

}  // namespace
}  // namespace haptel::haptics
