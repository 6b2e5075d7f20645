#pragma once
/// @file The haptic device drivers, each described once beside its code (sim,
/// udp, replay): its name as a device file gives it (`driver:`), what it
/// needs, what a run may do with it, its own checks of a device file and its
/// factory. ros2_control's hardware plugins are the model: a new driver is its
/// device's files and one RegisterDeviceDriver object; nothing outside this
/// registry asks a device's driver by name.
///
/// The built-in drivers register from their own files (sim_driver.cpp,
/// replay_driver.cpp, udp/udp_driver.cpp), in libraries linked whole
/// (haptics/CMakeLists.txt: `haptel_devices` is what a program links). A test
/// registers its own in its own file. Register before any thread reads it.
#include <functional>
#include <memory>
#include <string>

#include "haptel/config/device.hpp"
#include "haptel/config/run.hpp"
#include "haptel/haptics/device.hpp"

namespace haptel::haptics {

/// Where a device's calibration comes from (the run's DeviceCalibrationFor).
enum class CalibrationSource {
  kOptional,     ///< a file if the device file names one, else the device calibrates itself
  kBesideTrace,  ///< the file named, else the one recorded beside the trace
  kMeasured,     ///< a real device: only a measured file, made on that device, will do
  /// The device reports metres, radians and takes newtons itself (a
  /// joystick's axes mapped to metres): the identity calibration, or a file
  /// if the device file names one.
  kSelf,
};

struct DeviceDriver {
  std::string name;  ///< the device file's `driver:`
  /// Its arms are simulated: the automatic operator moves them, and a person
  /// has nothing to hold (a person at it drives by keys).
  bool simulated = false;
  /// It plays back a recorded trace (the device file's `replay.trace`, or --trace-in).
  bool reads_trace = false;
  /// A person moves it with the pointer and keys of the view's window (the
  /// mouse): a run with it needs the window (--view window).
  bool reads_window = false;
  CalibrationSource calibration = CalibrationSource::kMeasured;
  /// Its own checks of a device file naming it (ConfigFieldError naming the
  /// key), run by DeviceConfig::ValidateOrThrow after the common ones. May be empty.
  std::function<void(const DeviceConfig&)> check;
  /// Whether the device is there to be opened now, without opening it ("":
  /// yes; else a line saying what is missing: no display for the mouse, no
  /// joystick). The study console asks before it starts a trial. Empty: always.
  std::function<std::string(const DeviceConfig&)> available;
  /// Opens the device (ConfigError, std::runtime_error at set-up); `muscle`
  /// drives a simulated operator.
  std::function<std::unique_ptr<Device>(const DeviceConfig&, const OperatorConfig& muscle)> make;
};

/// A static object of this type in the driver's file is its registration.
/// std::invalid_argument when the name is taken or the factory is missing.
struct RegisterDeviceDriver {
  explicit RegisterDeviceDriver(DeviceDriver driver);
};

/// The driver named `name`, or null.
const DeviceDriver* FindDeviceDriver(const std::string& name);
/// The driver `device` names. std::logic_error when there is none (a config
/// that passed DeviceConfig::ValidateOrThrow names a registered one).
const DeviceDriver& DriverOf(const DeviceConfig& device);
/// "" when `device`'s driver says it is there to be opened, else its line
/// (DeviceDriver::available).
std::string DeviceUnavailable(const DeviceConfig& device);

}  // namespace haptel::haptics
