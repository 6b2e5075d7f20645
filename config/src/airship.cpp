#include "haptel/config/airship.hpp"

#include <cmath>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"

namespace haptel {

namespace check = config_check;

const char* AirshipIntegratorName(AirshipIntegrator integrator) {
  switch (integrator) {
    case AirshipIntegrator::kSemiImplicitEuler:
      return "semi-implicit-euler";
    case AirshipIntegrator::kMidpoint:
      return "midpoint";
    case AirshipIntegrator::kRk4:
      return "rk4";
  }
  return "?";
}

bool ParseAirshipIntegrator(const std::string& name, AirshipIntegrator* integrator) {
  for (AirshipIntegrator i : {AirshipIntegrator::kSemiImplicitEuler, AirshipIntegrator::kMidpoint,
                              AirshipIntegrator::kRk4}) {
    if (name == AirshipIntegratorName(i)) {
      *integrator = i;
      return true;
    }
  }
  return false;
}

void WindConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void AirshipConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (diameter >= length) check::Fail("diameter", "less than length (a prolate hull)", {"length"});
  if (helium_density >= air_density)
    check::Fail("helium_density", "less than air_density (a lifting gas)", {"air_density"});
}

double AirshipConfig::StillAirTopSpeed() const {
  return std::sqrt(2.0 * max_thrust /
                   (air_density * axial_drag_coefficient * std::pow(volume, 2.0 / 3.0)));
}

}  // namespace haptel
