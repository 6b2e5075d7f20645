#pragma once
// A Device for tests: returns scripted readings, records commands, can fail.
#include <atomic>

#include "haptel/haptics/device.hpp"

namespace haptel::test {

class ScriptedDevice final : public haptics::Device {
 public:
  explicit ScriptedDevice(bool left = false, bool right = true) {
    description_.name = "scripted";
    description_.has_side = {left, right};
  }
  const haptics::DeviceDescription& description() const override { return description_; }
  haptics::DeviceStatus ReadWrist(haptics::Side side, int64_t now_ns,
                                  haptics::WristRaw& out) override {
    const int s = haptics::Index(side);
    ++wrist_reads[s];
    last_read_ns[s] = now_ns;
    out.t_ns = now_ns;
    out.position = position[s];
    return status[s];
  }
  haptics::DeviceStatus ReadGlove(haptics::Side side, int64_t now_ns,
                                  haptics::GloveRaw& out) override {
    const int s = haptics::Index(side);
    ++glove_reads[s];
    out.t_ns = now_ns;
    out.sensors.fill(100.0);
    return status[s];
  }
  haptics::DeviceStatus WriteWristForce(haptics::Side side,
                                        const haptics::Vec3d& command) override {
    wrist_command[haptics::Index(side)] = command;
    return haptics::DeviceStatus::kOk;
  }
  haptics::DeviceStatus WriteFingerForces(
      haptics::Side side, const std::array<double, haptics::kFingers>& command) override {
    finger_command[haptics::Index(side)] = command;
    return haptics::DeviceStatus::kOk;
  }

  haptics::DeviceDescription description_;
  std::array<haptics::Vec3d, 2> position{};  ///< raw units
  std::array<haptics::DeviceStatus, 2> status{haptics::DeviceStatus::kOk,
                                              haptics::DeviceStatus::kOk};
  std::array<haptics::Vec3d, 2> wrist_command{};
  std::array<std::array<double, haptics::kFingers>, 2> finger_command{};
  std::array<std::atomic<uint64_t>, 2> wrist_reads{};
  std::array<std::atomic<uint64_t>, 2> glove_reads{};
  std::array<std::atomic<int64_t>, 2> last_read_ns{};
};

}  // namespace haptel::test
