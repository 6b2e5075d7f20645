#include "haptel/testing/gravity_on_sim.hpp"

#include <sstream>

#include "haptel/gravity/gravity_procedure.hpp"

namespace haptel::haptics {

GravitySampleReport SampleGravityOnSim(SimDevice& device, Side side,
                                       const ArmCalibration& calibration,
                                       const GravitySamplerConfig& config, int64_t start_ns) {
  GravityProcedureOptions options;
  options.auto_mode = true;
  options.start_ns = start_ns;
  std::ostringstream log;
  std::istringstream no_input;
  return SampleGravity(device, side, calibration, config, options, log, no_input);
}

}  // namespace haptel::haptics
