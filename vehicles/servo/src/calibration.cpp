#include "haptel/servo/calibration.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::servo {

double PulseFromCommand(const ServoChannelConfig& channel, double value) {
  if (std::isnan(value)) return channel.neutral_us;
  double v = std::clamp(value, -1.0, 1.0);
  if (channel.reversed) v = -v;
  return v >= 0.0 ? channel.neutral_us + v * (channel.max_us - channel.neutral_us)
                  : channel.neutral_us + v * (channel.neutral_us - channel.min_us);
}

double CommandFromPulse(const ServoChannelConfig& channel, double pulse_us) {
  if (std::isnan(pulse_us)) return 0.0;
  const double p = std::clamp(pulse_us, channel.min_us, channel.max_us);
  double v = 0.0;
  if (p > channel.neutral_us && channel.max_us > channel.neutral_us) {
    v = (p - channel.neutral_us) / (channel.max_us - channel.neutral_us);
  } else if (p < channel.neutral_us && channel.neutral_us > channel.min_us) {
    v = (p - channel.neutral_us) / (channel.neutral_us - channel.min_us);
  }
  v = std::clamp(v, -1.0, 1.0);
  return channel.reversed ? -v : v;
}

std::array<double, kBlimpChannels> PulsesFromCommands(
    const ServoControllerConfig& config, const std::array<double, kBlimpChannels>& values) {
  std::array<double, kBlimpChannels> out{};
  for (size_t i = 0; i < out.size(); ++i) out[i] = PulseFromCommand(config.channels[i], values[i]);
  return out;
}

std::array<double, kBlimpChannels> NeutralPulses(const ServoControllerConfig& config) {
  std::array<double, kBlimpChannels> out{};
  for (size_t i = 0; i < out.size(); ++i) out[i] = config.channels[i].neutral_us;
  return out;
}

namespace {
double& AxisOf(CameraServoChannel::Axis axis, CameraAim& aim) {
  switch (axis) {
    case CameraServoChannel::Axis::kPan:
      return aim.pan;
    case CameraServoChannel::Axis::kTilt:
      return aim.tilt;
    case CameraServoChannel::Axis::kZoom:
      break;
  }
  return aim.zoom;
}
}  // namespace

double CameraAxisCommand(const CameraServoChannel& axis, const CameraAim& aim) {
  const double span = axis.max - axis.min;
  if (!(span > 0.0)) return 0.0;
  CameraAim copy = aim;
  return std::clamp(2.0 * (AxisOf(axis.axis, copy) - axis.min) / span - 1.0, -1.0, 1.0);
}

void SetCameraAxis(const CameraServoChannel& axis, double command, CameraAim* aim) {
  AxisOf(axis.axis, *aim) =
      axis.min + 0.5 * (std::clamp(command, -1.0, 1.0) + 1.0) * (axis.max - axis.min);
}

}  // namespace haptel::servo
