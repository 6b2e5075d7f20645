#include "haptel/gravity/gravity_procedure.hpp"

#include <chrono>
#include <cmath>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>

#include "haptel/haptics/device_ticker.hpp"
#include "haptel/haptics/sim_device.hpp"

namespace haptel::haptics {

GravitySampleReport SampleGravity(Device& device, Side side, const ArmCalibration& calibration,
                                  const GravitySamplerConfig& config,
                                  const GravityProcedureOptions& options, std::ostream& log,
                                  std::istream& in) {
  SimDevice* sim = nullptr;
  if (options.auto_mode) {
    sim = dynamic_cast<SimDevice*>(&device);
    if (sim == nullptr)
      throw std::invalid_argument("unattended gravity sampling (--auto) needs the sim device");
  }
  if (!(options.rate_hz > 0.0 && options.rate_hz <= 100'000.0))
    throw std::invalid_argument("gravity sampling: the tick rate must be in (0, 100000] Hz");
  const auto tick_ns = static_cast<int64_t>(std::llround(1e9 / options.rate_hz));
  const char* const side_name = side == Side::kLeft ? "left" : "right";
  int vertex = 0;
  int vertices = 0;
  GravitySampler::PlaceArm place;
  if (sim != nullptr) {
    place = [sim, side](const Vec3d& target) {
      sim->Place(side, target);  // the calibrated frame taken for the true one
      sim->Release(side);        // only the device force holds the arm now
    };
  } else {
    place = [&](const Vec3d& target) {
      log << "  vertex " << ++vertex << " of " << vertices << ": bring the " << side_name
          << " wrist to (" << target[0] << ", " << target[1] << ", " << target[2]
          << ") m, hold it still, press Enter and let go." << std::endl;
      std::string line;
      if (!std::getline(in, line))
        throw std::runtime_error("the input ended before the gravity grid was sampled");
    };
  }
  GravitySampler sampler(device, side, calibration, config, place);
  vertices = sampler.vertex_count();
  log << "Gravity, " << side_name << " arm: " << vertices << " vertices, " << config.counts[0]
      << "x" << config.counts[1] << "x" << config.counts[2] << " over [" << config.box_min[0]
      << ", " << config.box_min[1] << ", " << config.box_min[2] << "]..[" << config.box_max[0]
      << ", " << config.box_max[1] << ", " << config.box_max[2] << "] m\n";
  DeviceTicker ticker(sim != nullptr, options.start_ns);
  const auto wall_start = std::chrono::steady_clock::now();
  int64_t now = ticker.now();
  while (sampler.Tick(now)) now = ticker.Next(tick_ns);
  GravitySampleReport report = sampler.report();
  report.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return report;
}

}  // namespace haptel::haptics
