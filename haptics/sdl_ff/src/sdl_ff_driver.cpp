// The `sdl-ff` driver in the device registry (haptel/haptics/device_drivers.hpp):
// a force-feedback joystick or wheel, or a game controller with rumble,
// through SDL (sdl_ff_device.hpp).
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/sdl_ff/sdl_ff_device.hpp"

namespace haptel::haptics {
namespace {

const RegisterDeviceDriver kSdlFfDriver{{
    .name = SdlFfDevice::kDriver,
    .simulated = false,
    .reads_trace = false,
    .calibration = CalibrationSource::kSelf,
    .check = nullptr,
    .available = SdlFfUnavailable,
    .make = [](const DeviceConfig& config, const OperatorConfig&) -> std::unique_ptr<Device> {
      return std::make_unique<SdlFfDevice>(config);
    },
}};

}  // namespace
}  // namespace haptel::haptics
