#pragma once
/// @file Standard flights of the airship model, each checking one piece of
/// its physics: the tests assert on them and `haptel bench blimp` reports
/// them, so both judge the same manoeuvre.
#include "haptel/config/airship.hpp"
#include "haptel/models/airship.hpp"

namespace haptel::models {

/// `config` ballasted to neutral buoyancy (payload_mass adjusted).
AirshipConfig NeutrallyBuoyant(AirshipConfig config);

/// Neutral, motors off, `seconds`: how far the centre of gravity moved, m.
double HoverDrift(const AirshipConfig& config, double seconds = 60.0);

/// Neutral, full power, 120 s: the forward airspeed reached, m/s.
double TopSpeed(const AirshipConfig& config);

/// Neutral, the power for `speed_kmh` in straight flight (drag ~ speed²)
/// for 90 s, then full left rudder: the mean yaw rate over 10 s after 20 s
/// of turning, rad/s. `reached_kmh` (optional): the speed before the turn.
double RudderYawRate(const AirshipConfig& config, double speed_kmh, double* reached_kmh = nullptr);

/// Aerodynamics and thrust off, neutral, started moving, rolled and
/// pitched: the largest |E(t) − E(0)| over `seconds`, relative to the
/// energy above rest. `finite` (optional): whether the state stayed finite.
double EnergyDrift(const AirshipConfig& config, double seconds = 600.0, bool* finite = nullptr);

/// The controls of the work-precision manoeuvre at time t: piecewise
/// constant on a 0.1 s grid (as a vehicle node's commands are), power,
/// rudder, elevator, helix plane and tail rotor all exercised.
AirshipControls ManoeuvreControls(double t_s);

}  // namespace haptel::models
