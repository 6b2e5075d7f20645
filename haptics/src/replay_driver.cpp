// The `replay` driver in the device registry (device_drivers.hpp): a recorded
// trace played back (trace.hpp), with the calibration recorded beside it.
#include <stdexcept>
#include <vector>

#include "haptel/config/check.hpp"
#include "haptel/config/error.hpp"
#include "haptel/haptics/device_drivers.hpp"
#include "haptel/haptics/trace.hpp"

namespace haptel::haptics {
namespace {

std::unique_ptr<Device> OpenReplay(const DeviceConfig& config, const OperatorConfig&) {
  std::vector<TraceRecord> records;
  try {
    records = ReadTrace(config.replay.trace);
  } catch (const std::runtime_error& e) {
    throw ConfigError(config.file.string() + ": key 'replay.trace': " + e.what());
  }
  DeviceDescription d;
  d.name = config.name;
  d.has_side = config.sides;
  d.wrist_force_limit = config.safety.wrist_force_limit;
  d.finger_force_limit = config.safety.finger_force_limit;
  d.has_glove = config.has_glove;
  d.has_grasp = config.has_grasp;
  return std::make_unique<ReplayDevice>(std::move(records), d, config.replay.loop);
}

const RegisterDeviceDriver kReplayDriver{{
    .name = "replay",
    .simulated = false,
    .reads_trace = true,
    .reads_window = false,
    .calibration = CalibrationSource::kBesideTrace,
    .check =
        [](const DeviceConfig& config) {
          if (config.replay.trace.empty())
            config_check::Fail("replay.trace", "a trace file for the replay driver");
        },
    .available = nullptr,
    .make = OpenReplay,
}};

}  // namespace
}  // namespace haptel::haptics
