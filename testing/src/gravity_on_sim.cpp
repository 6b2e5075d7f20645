#include "haptel/testing/gravity_on_sim.hpp"

#include <chrono>

namespace haptel::haptics {

GravitySampleReport SampleGravityOnSim(SimDevice& device, Side side,
                                       const ArmCalibration& calibration,
                                       const GravitySamplerConfig& config, int64_t start_ns) {
  constexpr int64_t kTickNs = 1'000'000;
  GravitySampler sampler(device, side, calibration, config, [&device, side](const Vec3d& vertex) {
    device.Place(side, vertex);  // the calibrated frame taken for the true one
    device.Release(side);        // only the device force holds the arm now
  });
  const auto wall_start = std::chrono::steady_clock::now();
  int64_t now = start_ns;
  while (sampler.Tick(now)) now += kTickNs;
  GravitySampleReport report = sampler.report();
  report.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

}  // namespace haptel::haptics
