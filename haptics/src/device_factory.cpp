#include "haptel/haptics/device_factory.hpp"

#include <stdexcept>

#include "haptel/config/error.hpp"
#include "haptel/haptics/sim_device.hpp"
#include "haptel/haptics/trace.hpp"
#include "haptel/udp/udp_device.hpp"

namespace haptel::haptics {

std::unique_ptr<Device> MakeDevice(const DeviceConfig& config, const OperatorConfig& muscle) {
  config.ValidateOrThrow();
  if (config.driver == "sim") return std::make_unique<SimDevice>(config, muscle);
  if (config.driver == "udp") return std::make_unique<UdpDevice>(config);
  if (config.driver == "replay") {
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
  throw std::logic_error("MakeDevice: driver '" + config.driver +
                         "' passed DeviceConfig::ValidateOrThrow but has no device");
}

}  // namespace haptel::haptics
