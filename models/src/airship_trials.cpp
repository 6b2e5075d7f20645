#include "haptel/models/airship_trials.hpp"

#include <cmath>

namespace haptel::models {

namespace {

void Fly(Airship& ship, const AirshipControls& controls, double seconds) {
  const double end = ship.time_s() + seconds;
  while (ship.time_s() < end - 1e-9) ship.Advance(std::min(0.05, end - ship.time_s()), controls);
}

}  // namespace

AirshipConfig NeutrallyBuoyant(AirshipConfig config) {
  config.payload_mass =
      (config.air_density - config.helium_density) * config.volume - config.structure_mass;
  return config;
}

double HoverDrift(const AirshipConfig& config, double seconds) {
  Airship ship(NeutrallyBuoyant(config));
  Fly(ship, {}, seconds);
  return ship.state().position.norm();
}

double TopSpeed(const AirshipConfig& config) {
  Airship ship(NeutrallyBuoyant(config));
  AirshipControls full;
  full.power = 1.0;
  Fly(ship, full, 120.0);
  return ship.Airspeed().x();
}

double RudderYawRate(const AirshipConfig& config, double speed_kmh, double* reached_kmh) {
  Airship ship(NeutrallyBuoyant(config));
  AirshipControls cruise;
  const double top_kmh = 35.0;  // the thesis's top speed, which the drag is fitted to
  cruise.power = std::min(1.0, std::pow(speed_kmh / top_kmh, 2));
  Fly(ship, cruise, 90.0);
  if (reached_kmh != nullptr) *reached_kmh = ship.Airspeed().x() * 3.6;
  cruise.rudder = 1.0;
  Fly(ship, cruise, 20.0);
  double turned = 0.0;
  double previous = ship.YawPitchRoll().x();
  const double start = ship.time_s();
  for (int i = 0; i < 200; ++i) {
    ship.Advance(0.05, cruise);
    const double yaw = ship.YawPitchRoll().x();
    turned += std::remainder(yaw - previous, 2.0 * M_PI);
    previous = yaw;
  }
  return turned / (ship.time_s() - start);
}

double EnergyDrift(const AirshipConfig& config, double seconds, bool* finite) {
  AirshipConfig c = NeutrallyBuoyant(config);
  c.aerodynamics = false;
  c.wind = WindConfig{};
  AirshipState start;
  start.velocity = {3.0, 0.5, -0.3};
  start.rates = {0.2, 0.05, 0.15};
  start.attitude = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) *
                   Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY());
  Airship ship(c);
  ship.set_state(start);
  const double e0 = ship.Energy();
  const double above_rest = e0 - Airship(c).Energy();
  double worst = 0.0;
  bool ok = true;
  for (double t = 0.0; t < seconds; t += 1.0) {
    ship.Advance(1.0, {});
    ok = ok && ship.Finite();
    worst = std::max(worst, std::abs(ship.Energy() - e0));
  }
  if (finite != nullptr) *finite = ok;
  return worst / above_rest;
}

AirshipControls ManoeuvreControls(double t_s) {
  // Held for each 0.1 s, like a node's commands; every step size used by
  // the benchmark divides 0.1 s, so no step straddles a change.
  const double t = std::floor(t_s * 10.0 + 1e-9) / 10.0;
  AirshipControls c;
  c.power = t < 5.0 ? 0.2 * t : 0.6 + 0.3 * std::sin(0.21 * t);
  c.rudder = 0.8 * std::sin(0.35 * t);
  c.elevator = 0.5 * std::sin(0.5 * t + 1.0);
  c.helix = t > 30.0 && t < 40.0 ? 0.8 : -0.2 * std::sin(0.15 * t);
  c.tail_rotor = t > 45.0 && t < 52.0 ? 1.0 : 0.0;
  return c;
}

}  // namespace haptel::models
