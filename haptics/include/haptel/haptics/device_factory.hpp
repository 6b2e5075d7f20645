#pragma once
/// @file Opens the device a DeviceConfig names: `sim`, `udp` or `replay`.
#include <memory>

#include "haptel/config/device.hpp"
#include "haptel/config/run.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

/// Throws ConfigFieldError (a `config` DeviceConfig::ValidateOrThrow refuses),
/// ConfigError (bad trace file, naming it) or std::runtime_error (a socket
/// that cannot be opened) at set-up. `muscle` drives the sim's operator.
std::unique_ptr<Device> MakeDevice(const DeviceConfig& config,
                                   const OperatorConfig& muscle = OperatorConfig{});

}  // namespace haptel::haptics
