#include "haptel/config/airship.hpp"

#include <cmath>

#include "airship_section.hpp"
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

void WindConfig::ValidateOrThrow() const {
  check::Vec3("mean", mean, -30.0, 30.0);
  check::Number("gust_rms", gust_rms, 0.0, 20.0);
  check::Number("gust_time_s", gust_time_s, 0.1, 600.0);
}

void AirshipConfig::ValidateOrThrow() const {
  check::Number("length", length, 0.1, 500.0);
  check::Number("diameter", diameter, 0.05, 100.0);
  if (diameter >= length) check::Fail("diameter", "less than length (a prolate hull)", {"length"});
  check::Number("volume", volume, 1e-3, 1e6);
  check::Number("air_density", air_density, 0.1, 2.0);
  check::Number("helium_density", helium_density, 0.0, 1.0);
  if (helium_density >= air_density)
    check::Fail("helium_density", "less than air_density (a lifting gas)", {"air_density"});
  check::Number("structure_mass", structure_mass, 0.01, 1e5);
  check::Number("payload_mass", payload_mass, 0.0, 1e5);
  check::Number("cg_below_cb", cg_below_cb, 0.0, 50.0);
  check::Number("axial_drag_coefficient", axial_drag_coefficient, 0.0, 5.0);
  check::Number("crossflow_drag_coefficient", crossflow_drag_coefficient, 0.0, 5.0);
  check::Number("fin_area", fin_area, 0.0, 1e3);
  check::Number("fin_lift_slope", fin_lift_slope, 0.0, 10.0);
  check::Number("fin_arm", fin_arm, 0.0, 250.0);
  check::Number("control_effectiveness", control_effectiveness, 0.0, 1.0);
  check::Number("max_surface_deg", max_surface_deg, 0.0, 60.0);
  check::Number("fin_onset_speed", fin_onset_speed, 0.01, 50.0);
  check::Number("max_thrust", max_thrust, 0.0, 1e5);
  check::Number("thrust_time_constant", thrust_time_constant, 0.01, 10.0);
  check::Number("propeller_x", propeller_x, -250.0, 250.0);
  check::Number("propeller_z", propeller_z, -50.0, 50.0);
  check::Number("max_helix_deg", max_helix_deg, 0.0, 120.0);
  check::Number("helix_rate_deg_s", helix_rate_deg_s, 1.0, 1000.0);
  check::Number("tail_thrust", tail_thrust, 0.0, 1e4);
  check::Number("tail_time_constant", tail_time_constant, 0.01, 10.0);
  check::Number("tail_arm", tail_arm, 0.0, 250.0);
  check::Number("tail_z", tail_z, -50.0, 50.0);
  check::Nested("wind", wind);
  check::Number("step_s", step_s, 1e-5, 0.1);
}

namespace config_detail {

AirshipConfig ReadAirship(YamlMap& section) {
  AirshipConfig c;
  c.length = section.Number("length", c.length);
  c.diameter = section.Number("diameter", c.diameter);
  c.volume = section.Number("volume", c.volume);
  c.air_density = section.Number("air_density", c.air_density);
  c.helium_density = section.Number("helium_density", c.helium_density);
  c.structure_mass = section.Number("structure_mass", c.structure_mass);
  c.payload_mass = section.Number("payload_mass", c.payload_mass);
  c.cg_below_cb = section.Number("cg_below_cb", c.cg_below_cb);
  c.axial_drag_coefficient = section.Number("axial_drag_coefficient", c.axial_drag_coefficient);
  c.crossflow_drag_coefficient =
      section.Number("crossflow_drag_coefficient", c.crossflow_drag_coefficient);
  c.fin_area = section.Number("fin_area", c.fin_area);
  c.fin_lift_slope = section.Number("fin_lift_slope", c.fin_lift_slope);
  c.fin_arm = section.Number("fin_arm", c.fin_arm);
  c.control_effectiveness = section.Number("control_effectiveness", c.control_effectiveness);
  c.max_surface_deg = section.Number("max_surface_deg", c.max_surface_deg);
  c.fin_onset_speed = section.Number("fin_onset_speed", c.fin_onset_speed);
  c.max_thrust = section.Number("max_thrust", c.max_thrust);
  c.thrust_time_constant = section.Number("thrust_time_constant", c.thrust_time_constant);
  c.propeller_x = section.Number("propeller_x", c.propeller_x);
  c.propeller_z = section.Number("propeller_z", c.propeller_z);
  c.max_helix_deg = section.Number("max_helix_deg", c.max_helix_deg);
  c.helix_rate_deg_s = section.Number("helix_rate_deg_s", c.helix_rate_deg_s);
  c.tail_thrust = section.Number("tail_thrust", c.tail_thrust);
  c.tail_time_constant = section.Number("tail_time_constant", c.tail_time_constant);
  c.tail_arm = section.Number("tail_arm", c.tail_arm);
  c.tail_z = section.Number("tail_z", c.tail_z);
  YamlMap wind = section.Map("wind");
  c.wind.mean = wind.Vec3("mean", c.wind.mean);
  c.wind.gust_rms = wind.Number("gust_rms", c.wind.gust_rms);
  c.wind.gust_time_s = wind.Number("gust_time_s", c.wind.gust_time_s);
  c.wind.seed =
      static_cast<uint64_t>(wind.Integer("seed", static_cast<int>(c.wind.seed), 0, 1 << 30));
  wind.Finish();
  const std::string integrator = section.String("integrator", AirshipIntegratorName(c.integrator));
  if (!ParseAirshipIntegrator(integrator, &c.integrator)) {
    section.Fail("integrator", "one of: semi-implicit-euler, midpoint, rk4");
  }
  c.step_s = section.Number("step_s", c.step_s);
  section.Finish();
  return c;
}

}  // namespace config_detail
double AirshipConfig::StillAirTopSpeed() const {
  return std::sqrt(2.0 * max_thrust /
                   (air_density * axial_drag_coefficient * std::pow(volume, 2.0 / 3.0)));
}

}  // namespace haptel
